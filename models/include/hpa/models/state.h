#pragma once
// The state type shared by truth and estimate (PX4 habit: the ground-truth switch changes the
// source, not the type), and the 19-element vector layout of docs/design.md section 4.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace hpa {

constexpr int kNx = 19;  // [p_WL_W, v_WL_W, p_WQ_W, v_WQ_W, q_WB (w,x,y,z), w_B]
constexpr int kNu = 4;   // rotor speeds, rad/s

using StateVector = Eigen::Matrix<double, kNx, 1>;
using InputVector = Eigen::Matrix<double, kNu, 1>;

/// Offsets of each block in StateVector.
struct StateIndex {
  static constexpr int kPayloadPos = 0;
  static constexpr int kPayloadVel = 3;
  static constexpr int kQuadPos = 6;
  static constexpr int kQuadVel = 9;
  static constexpr int kQuat = 12;  // w, x, y, z
  static constexpr int kBodyRate = 16;
};

/// Cable mode: the paper's m(k); taut = 1, slack = 0.
enum class CableMode { kSlack = 0, kTaut = 1 };

/// Name of a mode for logs ("slack" / "taut").
const char* ToString(CableMode mode);

/// Full system state as flight code sees it, from truth or from the estimator.
struct SystemState {
  double time_s = 0.0;
  Eigen::Vector3d p_WL_W = Eigen::Vector3d::Zero();          // payload position, world  (3)
  Eigen::Vector3d v_WL_W = Eigen::Vector3d::Zero();          // payload velocity, world  (3)
  Eigen::Vector3d p_WQ_W = Eigen::Vector3d::Zero();          // quadrotor position, world  (3)
  Eigen::Vector3d v_WQ_W = Eigen::Vector3d::Zero();          // quadrotor velocity, world  (3)
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();  // body attitude in world
  Eigen::Vector3d w_B = Eigen::Vector3d::Zero();             // body rate, body frame  (3)
  CableMode mode = CableMode::kTaut;                         // cable mode (estimated or true)
  bool payload_visible = true;  // payload seen in the last camera frame (false: predicted)
  // the estimator has lost the payload: its payload state is a guess, not a tracked estimate
  // (no detection for a while, or the free-fall prediction ran into the vehicle); truth: false
  bool payload_lost = false;
  // slack, and the last detections showed the payload held up (a hand, a gripper) rather than
  // falling; out of view it is then estimated where it was last seen; truth: the gripper holds it
  bool payload_supported = false;

  /// Packs into the 19-vector layout of StateIndex.
  StateVector ToVector() const;
  /// Unpacks a 19-vector (normalises the quaternion); keeps time, mode and the payload flags.
  void FromVector(const StateVector& x);
  /// True when every number is finite.
  bool AllFinite() const;
};

/// Command from the MPC (or geometric controller) to the body-rate controller.
struct BodyRateCommand {
  Eigen::Vector3d w_B_radps = Eigen::Vector3d::Zero();  // desired body rate  (3)
  double thrust_N = 0.0;                                // collective thrust
};

}  // namespace hpa
