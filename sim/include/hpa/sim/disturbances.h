#pragma once
// Disturbances of the world (a component of sim::World): scripted forces and impulses, velocity
// changes, and the air (the profile's wind with its gust and wind events, and the drag it makes on
// the quadrotor and the payload). Scenario events reach it through World::disturbances().

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "hpa/sim/wind.h"

namespace hpa::sim {

class World;
struct WorldConfig;

/// Body selector for disturbances.
enum class Body { kQuadrotor, kPayload };

/// Forces, impulses, velocity changes and wind acting on the world's bodies.
class Disturbances {
 public:
  /// Applies impulse_W_Ns (N s, world frame) at the body's centre of mass as a constant force
  /// over duration_s (rounded to whole steps, at least one).
  void ApplyImpulse(Body body, const Eigen::Vector3d& impulse_W_Ns, double duration_s = 0.01);
  /// Adds dv_W_mps (m/s, world frame) to the body's linear velocity at once (its free joint's
  /// qvel; a taut cable or a held gripper then acts on the new velocity from the next step).
  void AddVelocity(Body body, const Eigen::Vector3d& dv_W_mps);
  /// Constant force (N, world frame) on the quadrotor's centre of mass for duration_s.
  void SetWind(const Eigen::Vector3d& force_W_N, double duration_s);
  /// Adds a wind velocity (m/s, world frame) to the profile's wind for duration_s; it acts
  /// through the profile's drag (none in a world without aerodynamics).
  void SetWindVelocity(const Eigen::Vector3d& velocity_W_mps, double duration_s);
  /// The wind: its declaration, gust and events.
  const WindModel& wind() const { return *wind_; }
  /// Wind velocity at the vehicle now (m/s, world frame): steady part plus gust  (3)
  Eigen::Vector3d Wind_W_mps() const;
  /// Aerodynamic force on the quadrotor in the last step (N, world frame)  (3)
  const Eigen::Vector3d& aero_quad_W_N() const { return aero_quad_W_N_; }
  /// Aerodynamic force on the payload in the last step (N, world frame)  (3)
  const Eigen::Vector3d& aero_payload_W_N() const { return aero_payload_W_N_; }

 private:
  friend class World;
  struct TimedForce {
    Body body;
    Eigen::Vector3d force_W_N;  // (3)
    int64_t end_step;           // applied while step < end_step
  };
  Disturbances(World& world, const WorldConfig& config);
  // drops every scripted force
  void ClearForces() { forces_.clear(); }
  // the wind back to its start
  void ResetWind() { wind_->Reset(); }
  // this step's applied forces: drag and gust, then the scripted forces
  void Apply();
  // the gust's step and the drag on both bodies
  void ApplyAerodynamics();

  World& w_;  // the world these act on
  std::vector<TimedForce> forces_;
  std::unique_ptr<WindModel> wind_;                             // mean wind, gust, wind events
  Eigen::Vector3d aero_quad_W_N_ = Eigen::Vector3d::Zero();     // last drag on the quad  (3)
  Eigen::Vector3d aero_payload_W_N_ = Eigen::Vector3d::Zero();  // last drag on the payload  (3)
};

}  // namespace hpa::sim
