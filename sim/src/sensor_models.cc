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

void VioModel::Clear() {
  queue_.Clear();
  drift_rng_.seed(drift_seed_);
  drift_W_m_.setZero();
  yaw_drift_rad_ = 0.0;
  has_last_ = false;
  last_capture_s_ = 0.0;
  dropout_until_s_ = -1.0;
  in_dropout_ = false;
}

void VioModel::SetDrift(const VioDriftProfile& drift, uint64_t drift_seed) {
  drift_ = drift;
  drift_seed_ = drift_seed;
  Clear();
}

void VioModel::Capture(double time_s, const Eigen::Vector3d& p_WB_W_true,
                       const Eigen::Quaterniond& q_WB_true, const Eigen::Vector3d& v_WB_W_true) {
  // drift: random walks in position and yaw with the distance travelled since the last capture.
  // The displacement since then is reported rotated by the yaw drift (so the reported path
  // agrees with the reported velocity and nothing drifts while hovering), plus the position walk.
  Eigen::Vector3d p_WB_W = p_WB_W_true;
  Eigen::Quaterniond q_WB = q_WB_true;
  Eigen::Vector3d v_WB_W = v_WB_W_true;
  bool deliver = true;
  if (drift_.enabled) {
    std::normal_distribution<double> unit(0.0, 1.0);
    const Eigen::Vector3d step_W =
        has_last_ ? Eigen::Vector3d(p_WB_W_true - last_p_WB_W_) : Eigen::Vector3d::Zero();
    const double dt_s = has_last_ ? time_s - last_capture_s_ : 0.0;
    last_p_WB_W_ = p_WB_W_true;
    last_capture_s_ = time_s;
    has_last_ = true;
    const double sqrt_d = std::sqrt(step_W.norm());
    const Eigen::Matrix3d R_yaw_before =
        Eigen::AngleAxisd(yaw_drift_rad_, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    drift_W_m_ += (R_yaw_before - Eigen::Matrix3d::Identity()) * step_W;
    drift_W_m_.x() += drift_.position_drift_horizontal_m_per_sqrt_m * sqrt_d * unit(drift_rng_);
    drift_W_m_.y() += drift_.position_drift_horizontal_m_per_sqrt_m * sqrt_d * unit(drift_rng_);
    drift_W_m_.z() += drift_.position_drift_vertical_m_per_sqrt_m * sqrt_d * unit(drift_rng_);
    yaw_drift_rad_ += drift_.yaw_drift_rad_per_sqrt_m * sqrt_d * unit(drift_rng_);
    // dropouts: a Poisson process while tracking; when tracking resumes the VIO re-localises:
    // part of the drift is kept and it steps by the dead-reckoning error of the gap
    const double u = std::uniform_real_distribution<double>(0.0, 1.0)(drift_rng_);
    if (in_dropout_ && time_s >= dropout_until_s_) {
      in_dropout_ = false;
      drift_W_m_ *= drift_.relocalisation_keep_fraction;
      yaw_drift_rad_ *= drift_.relocalisation_keep_fraction;
      drift_W_m_.x() += drift_.relocalisation_jump_horizontal_m * unit(drift_rng_);
      drift_W_m_.y() += drift_.relocalisation_jump_horizontal_m * unit(drift_rng_);
      drift_W_m_.z() += drift_.relocalisation_jump_vertical_m * unit(drift_rng_);
      yaw_drift_rad_ += drift_.relocalisation_jump_yaw_rad * unit(drift_rng_);
    } else if (!in_dropout_ && u < 1.0 - std::exp(-drift_.dropout_rate_per_s * dt_s)) {
      in_dropout_ = true;
      dropout_until_s_ = time_s + drift_.dropout_duration_s;
    }
    deliver = !in_dropout_;
    const Eigen::Matrix3d R_yaw =
        Eigen::AngleAxisd(yaw_drift_rad_, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    p_WB_W = p_WB_W_true + drift_W_m_;
    q_WB = Eigen::Quaterniond(R_yaw) * q_WB_true;
    v_WB_W = R_yaw * v_WB_W_true;
  }
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
  if (deliver) queue_.Push(time_s, s);
}

std::optional<VioSample> VioModel::Take(double now_s) { return queue_.PopReady(now_s); }

}  // namespace hpa::sim
