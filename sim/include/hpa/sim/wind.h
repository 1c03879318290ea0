#pragma once
// The wind as a component of the world: the profile's mean wind, its gust (a first-order
// Gauss-Markov process per axis, Dryden's low-altitude form, advanced every physics step from a
// generator of its own) and a scripted wind event. It declares its row of the rate table like a
// sensor; the world's drag turns the wind it reports into forces.

#include <Eigen/Core>
#include <cstdint>
#include <random>

#include "hpa/sim/sensor_declaration.h"
#include "hpa/sim/world_profile.h"

namespace hpa::sim {

/// Mean wind, gust and wind events, on the physics clock.
class WindModel {
 public:
  /// The wind of `profile` on a clock of physics_hz, its gust drawn from a generator seeded by
  /// `seed`.
  WindModel(const WindProfile& profile, double physics_hz, uint64_t seed);
  /// Its row of the rate table.
  const SensorDeclaration& declaration() const { return declaration_; }
  /// Back to the start: the generator re-seeded, the gust drawn from its stationary
  /// distribution, no wind event.
  void Reset();
  /// True when it has a gust to advance.
  bool gusty() const { return profile_.gust_sigma_mps > 0.0; }
  /// Advances the gust one physics step for a vehicle moving at v_WQ_W (the gust's correlation
  /// length is travelled at the airspeed).
  void StepGust(const Eigen::Vector3d& v_WQ_W_mps);
  /// Adds velocity_W_mps to the wind from step `step` for `steps` physics steps.
  void SetEvent(const Eigen::Vector3d& velocity_W_mps, int64_t step, int64_t steps);
  /// Wind velocity at step `step` (m/s, world frame): mean plus gust plus a running event  (3)
  Eigen::Vector3d Wind_W_mps(int64_t step) const;

 private:
  WindProfile profile_;
  double dt_s_;
  uint64_t seed_;
  SensorDeclaration declaration_;
  std::mt19937_64 rng_;                                         // the gust's own generator
  Eigen::Vector3d gust_W_mps_ = Eigen::Vector3d::Zero();        // gust velocity, world  (3)
  Eigen::Vector3d event_wind_W_mps_ = Eigen::Vector3d::Zero();  // wind event's velocity  (3)
  int64_t event_wind_end_step_ = 0;                             // applied while step < this
};

}  // namespace hpa::sim
