#pragma once
// Simulated onboard sensors: a MEMS IMU (white noise + bias random walk) and a VIO pose stream
// (noisy, 30 Hz, delivered with a latency). Randomness only from the caller's generator.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <deque>
#include <optional>
#include <random>

#include "hpa/models/lockstep.h"
#include "hpa/models/sensor_types.h"
#include "hpa/sim/world_profile.h"

namespace hpa::sim {

/// Noise of the simulated IMU and VIO. Defaults: a BMI088-class IMU (datasheet noise densities;
/// bias walks typical of Kalibr/VINS configs for such parts) and a camera-IMU VIO of the kind the
/// paper flies (cm-level position, ~0.5 deg attitude; its 20 ms latency is in the RateTable).
struct SensorNoiseConfig {
  double gyro_noise_density_radps_rthz = 2.4e-4;  // BMI088: 0.014 deg/s/sqrt(Hz)
  double gyro_bias_walk_radps2_rthz = 2.0e-5;     // gyro bias random walk
  double accel_noise_density_mps2_rthz = 1.7e-3;  // BMI088: 175 ug/sqrt(Hz)
  double accel_bias_walk_mps3_rthz = 3.0e-4;      // accel bias random walk
  double vio_position_sigma_m = 0.01;             // per-sample position noise (1 sigma)
  double vio_attitude_sigma_rad = 0.01;           // per-sample attitude noise, each axis
  double vio_velocity_sigma_mps = 0.02;           // per-sample velocity noise
};

/// IMU model: adds white noise and a random-walk bias to the true body rate and specific force.
class ImuModel {
 public:
  /// `rng` must outlive the model (the World's single generator).
  ImuModel(const SensorNoiseConfig& noise, double period_s, std::mt19937_64* rng);
  /// A sample at time_s from the true body rate (body frame) and specific force
  /// R^T (a + g e3) (body frame); advances the bias random walk by one period.
  ImuSample Measure(double time_s, const Eigen::Vector3d& w_B_radps,
                    const Eigen::Vector3d& specific_force_B_mps2);
  /// Current gyro bias (rad/s), for tests and logs  (3)
  const Eigen::Vector3d& gyro_bias_B_radps() const { return gyro_bias_B_radps_; }
  /// Current accelerometer bias (m/s^2)  (3)
  const Eigen::Vector3d& accel_bias_B_mps2() const { return accel_bias_B_mps2_; }
  /// Sets both biases to zero (World::Reset).
  void ResetBias();

 private:
  Eigen::Vector3d Gaussian3(double sigma);
  SensorNoiseConfig noise_;
  double period_s_;
  std::mt19937_64* rng_;
  Eigen::Vector3d gyro_bias_B_radps_ = Eigen::Vector3d::Zero();  // (3)
  Eigen::Vector3d accel_bias_B_mps2_ = Eigen::Vector3d::Zero();  // (3)
};

/// VIO model: captures a noisy pose now, delivers it the rate table's VIO latency later (FIFO).
class VioModel {
 public:
  /// `rng` must outlive the model (the World's single generator).
  VioModel(const SensorNoiseConfig& noise, double latency_s, std::mt19937_64* rng);
  /// Captures the true pose and velocity at time_s, with noise, into the delivery queue.
  void Capture(double time_s, const Eigen::Vector3d& p_WB_W, const Eigen::Quaterniond& q_WB,
               const Eigen::Vector3d& v_WB_W);
  /// Oldest captured sample whose delivery time (capture + latency) is <= now_s, if any.
  std::optional<VioSample> Take(double now_s);
  /// Drops every queued sample and resets the drift, its generator (to drift_seed) and any
  /// dropout (World::Reset).
  void Clear();
  /// Switches the drift, dropouts and re-localisation jumps on (off by default: the true pose
  /// plus white noise). Their randomness comes from a generator of their own, seeded here, so
  /// the white noise stream is the same with and without drift.
  void SetDrift(const VioDriftProfile& drift, uint64_t drift_seed);
  /// Current position drift (m, world frame)  (3)
  const Eigen::Vector3d& drift_W_m() const { return drift_W_m_; }
  /// Current yaw drift (rad)
  double yaw_drift_rad() const { return yaw_drift_rad_; }

 private:
  SensorNoiseConfig noise_;
  std::mt19937_64* rng_;
  DelayLine<VioSample> queue_;
  VioDriftProfile drift_;
  uint64_t drift_seed_ = 0;
  std::mt19937_64 drift_rng_;
  Eigen::Vector3d drift_W_m_ = Eigen::Vector3d::Zero();  // position drift, world  (3)
  double yaw_drift_rad_ = 0.0;
  Eigen::Vector3d last_p_WB_W_ = Eigen::Vector3d::Zero();  // true position at last capture  (3)
  bool has_last_ = false;
  double last_capture_s_ = 0.0;
  double dropout_until_s_ = -1.0;  // no sample is delivered before this time
  bool in_dropout_ = false;
};

}  // namespace hpa::sim
