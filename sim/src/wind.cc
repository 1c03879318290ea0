// The wind component: mean wind, Dryden gust, wind events.

#include "hpa/sim/wind.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace hpa::sim {
namespace {

// The rate-table row of a wind profile: its gust's noise in one line.
SensorDeclaration WindDeclaration(const WindProfile& w, double physics_hz) {
  std::ostringstream noise;
  noise << "mean (" << w.mean_x_mps << ", " << w.mean_y_mps << ", " << w.mean_z_mps << ") m/s, ";
  if (w.gust_sigma_mps > 0.0) {
    noise << "gust sigma " << w.gust_sigma_mps << " m/s (vertical x" << w.gust_vertical_sigma_ratio
          << "), length " << w.gust_length_m << " m (vertical " << w.gust_vertical_length_m
          << " m)";
  } else {
    noise << "no gust";
  }
  return {"wind", physics_hz, 0.0, noise.str(), "world profile wind; wind events"};
}

}  // namespace

WindModel::WindModel(const WindProfile& profile, double physics_hz, uint64_t seed)
    : profile_(profile),
      dt_s_(1.0 / physics_hz),
      seed_(seed),
      declaration_(WindDeclaration(profile, physics_hz)),
      rng_(seed) {}

void WindModel::Reset() {
  rng_.seed(seed_);
  gust_W_mps_.setZero();
  event_wind_W_mps_.setZero();
  event_wind_end_step_ = 0;
  if (!gusty()) return;
  // the gust starts from its stationary distribution
  std::normal_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < 3; ++i) {
    gust_W_mps_(i) =
        profile_.gust_sigma_mps * (i == 2 ? profile_.gust_vertical_sigma_ratio : 1.0) * unit(rng_);
  }
}

// Per axis x' = a x + sigma sqrt(1 - a^2) n, exact for the step, a = exp(-dt / tau) with
// tau = L / airspeed (Dryden's low-altitude form at the vehicle's airspeed).
void WindModel::StepGust(const Eigen::Vector3d& v_WQ_W_mps) {
  const WindProfile& wind = profile_;
  const Eigen::Vector3d mean(wind.mean_x_mps, wind.mean_y_mps, wind.mean_z_mps);
  const double airspeed_mps = std::max(wind.gust_min_speed_mps, (v_WQ_W_mps - mean).norm());
  std::normal_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < 3; ++i) {
    const bool vertical = i == 2;
    const double sigma = wind.gust_sigma_mps * (vertical ? wind.gust_vertical_sigma_ratio : 1.0);
    const double length_m = vertical ? wind.gust_vertical_length_m : wind.gust_length_m;
    const double a = std::exp(-dt_s_ * airspeed_mps / length_m);
    gust_W_mps_(i) = a * gust_W_mps_(i) + sigma * std::sqrt(1.0 - a * a) * unit(rng_);
  }
}

void WindModel::SetEvent(const Eigen::Vector3d& velocity_W_mps, int64_t step, int64_t steps) {
  event_wind_W_mps_ = velocity_W_mps;
  event_wind_end_step_ = step + std::max<int64_t>(0, steps);
}

Eigen::Vector3d WindModel::Wind_W_mps(int64_t step) const {
  const WindProfile& w = profile_;
  const Eigen::Vector3d event_W =
      step < event_wind_end_step_ ? event_wind_W_mps_ : Eigen::Vector3d::Zero();
  return Eigen::Vector3d(w.mean_x_mps, w.mean_y_mps, w.mean_z_mps) + gust_W_mps_ + event_W;
}

}  // namespace hpa::sim
