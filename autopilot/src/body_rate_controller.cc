#include "hpa/autopilot/body_rate_controller.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "hpa/models/rotor_model.h"

namespace hpa {

BodyRateController::BodyRateController(const Params& params, const BodyRateGains& gains)
    : params_(params), gains_(gains) {}

void BodyRateController::Reset() {
  integral_radps2_.setZero();
  w_prev_radps_.setZero();
  has_prev_ = false;
}

InputVector BodyRateController::AllocateWithThrustPriority(const Params& params,
                                                           const Eigen::Vector4d& wrench,
                                                           double* moment_scale) {
  const double f_min_N = params.k_f_N_per_radps2 * std::pow(params.motor_speed_min_radps, 2);
  const double f_max_N = params.k_f_N_per_radps2 * std::pow(params.motor_speed_max_radps, 2);
  const Eigen::Matrix4d alloc_inv = AllocationMatrix(params).inverse();

  // collective thrust first, inside what four rotors can give
  const double thrust_N = std::clamp(wrench(0), 4.0 * f_min_N, 4.0 * f_max_N);
  const Eigen::Vector4d f_thrust = alloc_inv.col(0) * thrust_N;  // equal share per rotor
  const Eigen::Vector4d f_moment = alloc_inv.rightCols<3>() * wrench.tail<3>();

  // largest alpha in [0, 1] with f_min <= f_thrust + alpha f_moment <= f_max
  double alpha = 1.0;
  for (int i = 0; i < 4; ++i) {
    if (f_moment(i) > 0.0) {
      alpha = std::min(alpha, (f_max_N - f_thrust(i)) / f_moment(i));
    } else if (f_moment(i) < 0.0) {
      alpha = std::min(alpha, (f_min_N - f_thrust(i)) / f_moment(i));
    }
  }
  alpha = std::clamp(alpha, 0.0, 1.0);
  if (moment_scale != nullptr) *moment_scale = alpha;

  const Eigen::Vector4d f = f_thrust + alpha * f_moment;
  InputVector w;
  for (int i = 0; i < 4; ++i) {
    // the clamp only removes rounding: alpha already keeps f inside [f_min, f_max]
    w(i) = std::clamp(std::sqrt(std::max(f(i), 0.0) / params.k_f_N_per_radps2),
                      params.motor_speed_min_radps, params.motor_speed_max_radps);
  }
  return w;
}

InputVector BodyRateController::Update(const BodyRateCommand& cmd,
                                       const Eigen::Vector3d& w_B_measured_radps, double dt_s) {
  status_ = BodyRateStatus();
  const bool valid = cmd.w_B_radps.allFinite() && std::isfinite(cmd.thrust_N) &&
                     w_B_measured_radps.allFinite() && std::isfinite(dt_s) && dt_s > 0.0;
  if (!valid) {
    // safe output: level hover wrench, loop memory cleared
    Reset();
    status_.input_valid = false;
    status_.moment_scale = 0.0;
    Eigen::Vector4d wrench(params_.HoverThrustN(), 0.0, 0.0, 0.0);
    return AllocateWithThrustPriority(params_, wrench);
  }

  const Eigen::Vector3d& j = params_.inertia_B_kgm2;
  const Eigen::Vector3d error = cmd.w_B_radps - w_B_measured_radps;

  // derivative on measurement (no kick on setpoint steps)
  Eigen::Vector3d w_dot = Eigen::Vector3d::Zero();
  if (has_prev_) w_dot = (w_B_measured_radps - w_prev_radps_) / dt_s;
  w_prev_radps_ = w_B_measured_radps;
  has_prev_ = true;

  const Eigen::Vector3d accel_cmd =
      gains_.kp_per_s.cwiseProduct(error) + integral_radps2_ - gains_.kd.cwiseProduct(w_dot);
  const Eigen::Vector3d jw = j.cwiseProduct(w_B_measured_radps);
  const Eigen::Vector3d moment_Nm = j.cwiseProduct(accel_cmd) + w_B_measured_radps.cross(jw);

  Eigen::Vector4d wrench;
  wrench << cmd.thrust_N, moment_Nm;
  double alpha = 1.0;
  const InputVector w = AllocateWithThrustPriority(params_, wrench, &alpha);
  status_.moment_scale = alpha;
  status_.saturated = alpha < 1.0;

  // integrate, frozen while saturated (anti-windup), clamped
  if (!status_.saturated) {
    integral_radps2_ += gains_.ki_per_s2.cwiseProduct(error) * dt_s;
    integral_radps2_ = integral_radps2_.cwiseMax(-gains_.integral_limit_radps2)
                           .cwiseMin(gains_.integral_limit_radps2);
  }
  return w;
}

}  // namespace hpa
