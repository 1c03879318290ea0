#pragma once
// Private to the controller library: helpers the OCP's dynamics/building code (ocp.cc) and its
// cost terms (ocp_terms.cc) share.

#include <Eigen/Core>

#include "hpa/controller/ocp.h"

namespace hpa {
namespace ocp_internal {

constexpr double kCamMinDepthM = 0.12;  // slack L_cam off nearer the lens plane (thrown payload)

// The payload's offset from the quadrotor d = x_L - x_Q as L_cam sees it at stage k: in a slack
// stage no farther than the cable's length, and without the model's free fall when the payload
// is supported (ocp.cc). When d_d is not null it receives d(seen) / d(d).
Eigen::Vector3d SeenPayloadOffset(const Ocp& ocp, int k, const Eigen::Vector3d& d_W,
                                  Eigen::Matrix3d* d_d);

// Rotation matrix of a (unit) quaternion w, x, y, z, for any scalar type.
template <typename T>
Eigen::Matrix<T, 3, 3> RotationOf(const T& w, const T& x, const T& y, const T& z) {
  Eigen::Matrix<T, 3, 3> r;
  r << T(1) - T(2) * (y * y + z * z), T(2) * (x * y - w * z), T(2) * (x * z + w * y),
      T(2) * (x * y + w * z), T(1) - T(2) * (x * x + z * z), T(2) * (y * z - w * x),
      T(2) * (x * z - w * y), T(2) * (y * z + w * x), T(1) - T(2) * (x * x + y * y);
  return r;
}

// p_C for any scalar type in the quaternion (the positions enter linearly).
template <typename T>
Eigen::Matrix<T, 3, 1> CameraPoint(const Ocp& ocp, const Eigen::Vector3d& d_W,
                                   const Eigen::Matrix<T, 4, 1>& q) {
  const Eigen::Matrix<T, 3, 3> r = RotationOf<T>(q(0), q(1), q(2), q(3));
  const Eigen::Matrix<T, 3, 1> d_B = r.transpose() * d_W.cast<T>();
  return ocp.R_BC.transpose().cast<T>() * (d_B - ocp.t_BC_B_m.cast<T>());
}

/// d p_C / d q (3 x 4) of CameraPoint at the unit quaternion q (w, x, y, z), hand-derived:
/// column j is R_BC^T (d R / d q_j)^T d_W.
Eigen::Matrix<double, 3, 4> CameraPointQuatJacobian(const Ocp& ocp, const Eigen::Vector3d& d_W,
                                                    const Eigen::Vector4d& q);

// State reference of stage k (the terminal one past the horizon).
inline const StateVector& StageStateReference(const Ocp& ocp, int k) {
  return ocp.x_ref[std::min<int>(k, ocp.x_ref.size() - 1)];
}

// Slack L_cam's dead zone as a fraction of the half field of view: a held payload's
// (OcpWeights::cam_held_deadzone_fraction) or a free one's.
inline double SlackDeadzoneFraction(const Ocp& ocp) {
  return ocp.payload_supported ? ocp.weights.cam_held_deadzone_fraction
                               : ocp.weights.cam_slack_deadzone_fraction;
}

}  // namespace ocp_internal
}  // namespace hpa
