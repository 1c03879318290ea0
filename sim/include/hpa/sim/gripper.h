#pragma once
// The gripper of the world (a component of sim::World): a mocap hand that welds the payload to
// itself, carries it along a minimum-jerk path and lets it go; its rod turns solid once a released
// payload is clear of it. Scenario events reach it through World::gripper().

#include <Eigen/Core>
#include <cstdint>

namespace hpa::sim {

class World;

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

 private:
  friend class World;
  explicit Gripper(World& world) : w_(world) {}
  // back to no hold, no motion and no hand (World::Reset, before the state is set)
  void Reset();
  // opens the weld and stops the motion (a release, or a gripper fault letting go)
  void Open();
  // moves the mocap body along its path to the current step
  void Update();
  // the rod's collision switch: solid once used, not holding and clear of the payload
  void UpdateContact();
  // payload sphere to the rod's capsule, surface to surface (m)
  double PayloadDistance() const;

  World& w_;  // the world this gripper is part of
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
