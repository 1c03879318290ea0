#include "hpa/sim/sensor_models.h"

#include <cmath>

namespace hpa::sim {

ImuModel::ImuModel(const SensorNoiseConfig& noise, double period_s, std::mt19937_64* rng)
    : noise_(noise), period_s_(period_s), rng_(rng) {}

Eigen::Vector3d ImuModel::Gaussian3(double sigma) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) v(i) = sigma * normal(*rng_);
  return v;
}

void ImuModel::ResetBias() {
  gyro_bias_B_radps_.setZero();
  accel_bias_B_mps2_.setZero();
}

ImuSample ImuModel::Measure(double time_s, const Eigen::Vector3d& w_B_radps,
                            const Eigen::Vector3d& specific_force_B_mps2) {
  // discrete white noise: sigma = density / sqrt(period); bias walk: sigma = walk * sqrt(period)
  const double sqrt_period = std::sqrt(period_s_);
  ImuSample s;
  s.time_s = time_s;
  s.gyro_B_radps = w_B_radps + gyro_bias_B_radps_ +
                   Gaussian3(noise_.gyro_noise_density_radps_rthz / sqrt_period);
  s.accel_B_mps2 = specific_force_B_mps2 + accel_bias_B_mps2_ +
                   Gaussian3(noise_.accel_noise_density_mps2_rthz / sqrt_period);
  gyro_bias_B_radps_ += Gaussian3(noise_.gyro_bias_walk_radps2_rthz * sqrt_period);
  accel_bias_B_mps2_ += Gaussian3(noise_.accel_bias_walk_mps3_rthz * sqrt_period);
  return s;
}

VioModel::VioModel(const SensorNoiseConfig& noise, double latency_s, std::mt19937_64* rng)
    : noise_(noise), rng_(rng), queue_(latency_s) {}

void VioModel::Capture(double time_s, const Eigen::Vector3d& p_WB_W, const Eigen::Quaterniond& q_WB,
                       const Eigen::Vector3d& v_WB_W) {
  std::normal_distribution<double> normal(0.0, 1.0);
  auto gaussian3 = [&](double sigma) {
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) v(i) = sigma * normal(*rng_);
    return v;
  };
  VioSample s;
  s.time_s = time_s;
  s.p_WB_W = p_WB_W + gaussian3(noise_.vio_position_sigma_m);
  // attitude error: a small rotation about a random body-frame axis
  const Eigen::Vector3d dtheta_B = gaussian3(noise_.vio_attitude_sigma_rad);
  const double angle = dtheta_B.norm();
  const Eigen::Quaterniond dq = angle > 0
                                    ? Eigen::Quaterniond(Eigen::AngleAxisd(angle, dtheta_B / angle))
                                    : Eigen::Quaterniond::Identity();
  s.q_WB = (q_WB * dq).normalized();
  s.v_WB_W = v_WB_W + gaussian3(noise_.vio_velocity_sigma_mps);
  queue_.Push(time_s, s);
}

std::optional<VioSample> VioModel::Take(double now_s) { return queue_.PopReady(now_s); }

}  // namespace hpa::sim
