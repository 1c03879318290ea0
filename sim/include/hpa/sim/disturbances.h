#pragma once
// Disturbances of a world (a component of sim::World and of sim::TeamWorld): scripted forces and
// impulses, velocity changes, and the air (the profile's wind with its gust and wind events, and
// the drag it makes on each vehicle and the payload). The world binds it to its bodies
// (DisturbancesBinding) and steps it; scenario events reach it through World::disturbances() or
// TeamWorld::disturbances().

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "hpa/models/params.h"
#include "hpa/sim/wind.h"
#include "hpa/sim/world_profile.h"

// MuJoCo's model and data, only pointed to here (sim/src includes MuJoCo)
struct mjModel_;
struct mjData_;

namespace hpa::sim {

/// Body selector of the single vehicle's world.
enum class Body { kQuadrotor, kPayload };

/// A body disturbances act on: the payload, or a vehicle by its index (a World's quadrotor is
/// vehicle 0; a TeamWorld's vehicles are 0 .. N-1).
struct BodyRef {
  /// The single world's quadrotor (vehicle 0) or payload.
  BodyRef(Body body) : index(body == Body::kPayload ? -1 : 0) {}  // NOLINT: World names a Body
  /// Body `body_index`: -1 the payload, 0 .. N-1 that vehicle (TeamWorld's body numbers).
  explicit BodyRef(int body_index) : index(body_index) {}
  int index = 0;  // -1: the payload; 0 .. N-1: that vehicle
};

/// One vehicle a Disturbances pushes and drags: its MuJoCo body, its free joint and its numbers.
struct DisturbedVehicle {
  int body = -1;                   // MuJoCo body id
  int qpos = -1;                   // first qpos of its free joint [p, q (w, x, y, z)]
  int dof = -1;                    // first dof of its free joint [v (world), w (body)]
  const Params* params = nullptr;  // its simulated numbers (the drag reads body_half_size_m)
};

/// What a Disturbances reaches of the world it acts in, filled by that world: MuJoCo's model and
/// data, the bodies it pushes, the numbers its drag reads and the world's clock. Every pointer
/// outlives the Disturbances (the world owns them all).
struct DisturbancesBinding {
  mjModel_* model = nullptr;                 // the world's MuJoCo model
  mjData_* data = nullptr;                   // the world's MuJoCo data
  std::vector<DisturbedVehicle> vehicles;    // the vehicles (one in a World)  (N)
  int payload_body = -1;                     // the payload's MuJoCo body id
  int payload_dof = -1;                      // first dof of the payload's free joint
  const double* payload_radius_m = nullptr;  // the payload's drag sphere
  const AeroProfile* aero = nullptr;         // the drag (disabled: none)
  const int64_t* step = nullptr;             // the world's physics steps since Reset
};

/// Forces, impulses, velocity changes and wind acting on the world's bodies.
class Disturbances {
 public:
  /// Bound to a world's bodies; the wind of `wind` at physics_hz, its gust drawn from wind_seed.
  Disturbances(const DisturbancesBinding& binding, const WindProfile& wind, double physics_hz,
               uint64_t wind_seed);

  /// Applies impulse_W_Ns (N s, world frame) at the body's centre of mass as a constant force
  /// over duration_s (rounded to whole steps, at least one). A body the world does not have
  /// throws std::out_of_range.
  void ApplyImpulse(BodyRef body, const Eigen::Vector3d& impulse_W_Ns, double duration_s = 0.01);
  /// Adds dv_W_mps (m/s, world frame) to the body's linear velocity at once (its free joint's
  /// qvel; a taut cable or a held gripper then acts on the new velocity from the next step). A
  /// body the world does not have throws std::out_of_range.
  void AddVelocity(BodyRef body, const Eigen::Vector3d& dv_W_mps);
  /// Constant force (N, world frame) on every vehicle's centre of mass for duration_s.
  void SetWind(const Eigen::Vector3d& force_W_N, double duration_s);
  /// Adds a wind velocity (m/s, world frame) to the profile's wind for duration_s; it acts
  /// through the profile's drag (none in a world without aerodynamics).
  void SetWindVelocity(const Eigen::Vector3d& velocity_W_mps, double duration_s);
  /// The wind: its declaration, gust and events.
  const WindModel& wind() const { return *wind_; }
  /// Wind velocity now (m/s, world frame): steady part plus gust, the same at every body  (3)
  Eigen::Vector3d Wind_W_mps() const;
  /// Aerodynamic force on vehicle 0 (a World's quadrotor) in the last step (N, world frame)  (3)
  const Eigen::Vector3d& aero_quad_W_N() const { return aero_vehicle_W_N_.front(); }
  /// Aerodynamic force on vehicle `vehicle` in the last step (N, world frame); a vehicle the
  /// world does not have throws std::out_of_range  (3)
  const Eigen::Vector3d& aero_vehicle_W_N(int vehicle) const;
  /// Aerodynamic force on the payload in the last step (N, world frame)  (3)
  const Eigen::Vector3d& aero_payload_W_N() const { return aero_payload_W_N_; }

  // What the owning world calls, in its step order.
  /// Drops every scripted force (a Reset).
  void ClearForces() { forces_.clear(); }
  /// The wind back to its start (a Reset).
  void ResetWind() { wind_->Reset(); }
  /// This step's applied forces into MuJoCo's xfrc_applied (zeroed first): drag and gust, then
  /// the scripted forces; those ending with this step are dropped.
  void Apply();

 private:
  struct TimedForce {
    int body;                   // BodyRef::index
    Eigen::Vector3d force_W_N;  // (3)
    int64_t end_step;           // applied while step < end_step
  };
  // MuJoCo body id of a body index (std::out_of_range for one the world does not have)
  int BodyId(int index, const char* caller) const;
  // the gust's step (at vehicle 0's airspeed) and the drag on every vehicle and the payload
  void ApplyAerodynamics();

  DisturbancesBinding b_;  // the world these act on
  std::vector<TimedForce> forces_;
  std::unique_ptr<WindModel> wind_;                // mean wind, gust, wind events
  std::vector<Eigen::Vector3d> aero_vehicle_W_N_;  // last drag on each vehicle  (N x 3)
  Eigen::Vector3d aero_payload_W_N_ = Eigen::Vector3d::Zero();  // last drag on the payload  (3)
};

}  // namespace hpa::sim
