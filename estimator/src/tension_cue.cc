#include "hpa/estimator/tension_cue.h"

#include <cmath>

namespace hpa {

TensionCue::TensionCue(const Params& params, const TensionCueConfig& config, bool start_slack)
    : params_(params),
      config_(config),
      thrust_N_(params.HoverThrustN()),
      tension_N_(start_slack ? 0.0 : params.payload_mass_kg * params.gravity_mps2),
      slack_(start_slack) {}

bool TensionCue::Update(double time_s, const Eigen::Vector3d& specific_force_B_mps2,
                        const Eigen::Matrix3d& R_WB, double thrust_command_N,
                        const Eigen::Vector3d& xi_W) {
  if (!std::isfinite(time_s) || !specific_force_B_mps2.allFinite() || !R_WB.allFinite() ||
      !std::isfinite(thrust_command_N) || !xi_W.allFinite()) {
    return slack_;
  }
  if (started_ && time_s <= last_time_s_) return slack_;
  const double dt_s = started_ ? time_s - last_time_s_ : 0.0;
  started_ = true;
  last_time_s_ = time_s;
  // the rotors reach a commanded thrust through their spin-up lag
  thrust_N_ +=
      (1.0 - std::exp(-dt_s / params_.motor_time_constant_s)) * (thrust_command_N - thrust_N_);
  const Eigen::Vector3d cable_force_W_N =
      params_.quad_mass_kg * (R_WB * specific_force_B_mps2) - thrust_N_ * R_WB.col(2);
  const double tension_raw_N = cable_force_W_N.dot(xi_W);
  tension_N_ +=
      (1.0 - std::exp(-dt_s / config_.filter_time_constant_s)) * (tension_raw_N - tension_N_);
  const double weight_N = params_.payload_mass_kg * params_.gravity_mps2;
  if (slack_ && tension_N_ > config_.taut_fraction * weight_N) slack_ = false;
  if (!slack_ && tension_N_ < config_.slack_fraction * weight_N) slack_ = true;
  return slack_;
}

}  // namespace hpa
