#pragma once
// The gripper of the world (a component of sim::World): a mocap hand that welds the payload to
// itself, carries it along a minimum-jerk path and lets it go; its rod turns solid once a released
// payload is clear of it. Scenario events reach it through World::gripper(). The world binds it
// to the scene's hand, weld and payload (GripperBinding); it reaches nothing else of that world.

#include <Eigen/Core>
#include <cstdint>

// MuJoCo's model and data, only pointed to here (sim/src includes MuJoCo)
struct mjModel_;
struct mjData_;

namespace hpa::sim {

class Faults;

/// What the Gripper reaches of its world, filled by that world: MuJoCo's model and data, the
/// ids of the hand, its weld, its rod and the payload's joint, the payload's radius, whether
/// the world simulates contact, the gripper faults (a late release is recorded in them) and the
/// world's clock. Every pointer outlives the gripper.
struct GripperBinding {
  mjModel_* model = nullptr;           // the world's MuJoCo model (the weld's switch is in it)
  mjData_* data = nullptr;             // the world's MuJoCo data
  int mocap = -1;                      // the hand's mocap index
  int weld = -1;                       // the hand-payload weld (equality constraint id)
  int rod_geom = -1;                   // the hand's rod (-1: the scene has none)
  int payload_qpos = -1;               // first qpos of the payload's free joint
  const double* payload_radius_m = nullptr;  // the world's payload radius
  bool contact = false;                // the world simulates contact (the rod can turn solid)
  Faults* faults = nullptr;            // gripper faults (a deferred release; null: none)
  const int64_t* step = nullptr;       // the world's physics steps since Reset
  const double* t0_s = nullptr;        // the world's time at Reset (s)
};

/// The world's gripper: grab, move, release (events), and whether it holds the payload.
class Gripper {
 public:
  /// Welds the payload to the gripper where it is now (moves the mocap body onto it first).
  void Grab();
  /// Moves the gripper (and a held payload) to to_W_m along a minimum-jerk path over duration_s.
  void Move(const Eigen::Vector3d& to_W_m, double duration_s);
  /// Lets the payload go (unless a gripper fault defers the release).
  void Release();
  /// True while the gripper holds the payload.
  bool active() const;

 public:
  /// Bound to the world's hand; every pointer of the binding must be set.
  explicit Gripper(const GripperBinding& binding);

  // What the owning world calls, in its step order.
  /// Back to no hold, no motion and no hand (the world's Reset, before the state is set).
  void Reset();
  /// Opens the weld and stops the motion (a release, or a gripper fault letting go).
  void Open();
  /// Moves the mocap body along its path to the current step.
  void Update();
  /// The rod's collision switch: solid once used, not holding and clear of the payload.
  void UpdateContact();

 private:
  // payload sphere to the rod's capsule, surface to surface (m)
  double PayloadDistance() const;
  // the world's time now (s)
  double time_s() const;

  GripperBinding b_;  // the world this gripper is part of
  // motion: min-jerk from start to goal over [start_step, end_step]
  bool moving_ = false;
  Eigen::Vector3d from_W_m_ = Eigen::Vector3d::Zero();  // (3)
  Eigen::Vector3d to_W_m_ = Eigen::Vector3d::Zero();    // (3)
  int64_t start_step_ = 0;
  int64_t end_step_ = 0;
  bool solid_ = false;  // the rod collides (flight contact, not holding, clear)
  bool used_ = false;   // an event has grabbed with or moved the gripper in this run
};

}  // namespace hpa::sim
