#pragma once
// Quadrotor state filter: error-state EKF with IMU prediction (500 Hz, gyro and accelerometer
// bias states) and delayed VIO pose + velocity updates (30 Hz) applied at their capture time.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>

#include "hpa/estimator/filter_status.h"
#include "hpa/models/params.h"
#include "hpa/models/ring_queue.h"
#include "hpa/models/sensor_types.h"
#include "hpa/models/state.h"

namespace hpa {

/// Noise model and tuning of the quadrotor filter (continuous-time densities, 1-sigma values).
/// Defaults: a BMI088-class IMU's datasheet densities and a cm-level VIO, the same figures the
/// simulator's SensorNoiseConfig uses (sim/include/hpa/sim/sensor_models.h).
struct QuadFilterConfig {
  double gyro_noise_radps_per_sqrthz = 2.4e-4;     // white gyro noise density
  double accel_noise_mps2_per_sqrthz = 1.7e-3;     // white accelerometer noise density
  double gyro_bias_walk_radps2_per_sqrthz = 2e-5;  // gyro bias random walk
  double accel_bias_walk_mps3_per_sqrthz = 3e-4;   // accelerometer bias random walk
  double vio_position_std_m = 0.01;                // VIO position noise, per axis
  double vio_attitude_std_rad = 0.01;              // VIO attitude noise, per axis
  double vio_velocity_std_mps = 0.02;              // VIO velocity noise, per axis
  double initial_position_std_m = 0.02;            // initial covariance, per axis
  double initial_velocity_std_mps = 0.05;          // initial covariance, per axis
  double initial_attitude_std_rad = 0.02;          // initial covariance, per axis
  double initial_gyro_bias_std_radps = 0.01;       // initial covariance, per axis
  double initial_accel_bias_std_mps2 = 0.1;        // initial covariance, per axis
  double history_s = 0.5;                          // how late a VIO sample may arrive
  // VIO gate: NIS over 50 rejects (9 dof: the 99.9999% quantile is 45); the fourth rejection in a
  // row is accepted anyway (the filter, not VIO, is then off)
  InnovationGate vio_gate = {50.0, 3};
};

/// Nominal state of the quadrotor filter.
struct QuadFilterState {
  double time_s = 0.0;
  Eigen::Vector3d p_WB_W = Eigen::Vector3d::Zero();             // body position, world  (3)
  Eigen::Vector3d v_WB_W = Eigen::Vector3d::Zero();             // body velocity, world  (3)
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();     // body attitude
  Eigen::Vector3d gyro_bias_B_radps = Eigen::Vector3d::Zero();  // gyro bias  (3)
  Eigen::Vector3d accel_bias_B_mps2 = Eigen::Vector3d::Zero();  // accelerometer bias  (3)
  Eigen::Vector3d w_B_radps = Eigen::Vector3d::Zero();          // bias-corrected body rate  (3)
};

/// Filter state at a known vehicle state (pose, velocity, body rate), biases zero.
QuadFilterState QuadFilterStateFrom(const SystemState& state);

using Matrix15d = Eigen::Matrix<double, 15, 15>;
using Vector15d = Eigen::Matrix<double, 15, 1>;

/// Error-state EKF. Error state (15): [dp_W, dv_W, dtheta_B, dbias_gyro, dbias_accel], with the
/// attitude error on the right: R_true = R_est Exp(dtheta).
class QuadFilter {
 public:
  /// Starts at `initial` with the configured initial standard deviations.
  QuadFilter(const Params& params, const QuadFilterConfig& config, const QuadFilterState& initial);

  /// Propagates to imu.time_s with the trapezoid of the previous and this sample.
  FilterStatus Predict(const ImuSample& imu);

  /// Applies a VIO sample at its capture time (rewinds the history, updates, re-propagates).
  FilterStatus UpdateVio(const VioSample& vio);

  /// Current (latest IMU time) state and its 15x15 error covariance.
  const QuadFilterState& state() const { return state_; }
  const Matrix15d& covariance() const { return covariance_; }
  /// Counts of refused IMU samples and of accepted, rejected and forced VIO updates.
  const FilterCounts& counts() const { return counts_; }

  /// State at a past time from the history (nearest kept sample at or before time_s), or the
  /// current state if time_s is newer; nullopt if older than the history.
  std::optional<QuadFilterState> StateAt(double time_s) const;

  /// Error-state vector of `truth` relative to `estimate` (what NEES is computed on).
  static Vector15d ErrorState(const QuadFilterState& estimate, const QuadFilterState& truth);

 private:
  struct Entry {
    QuadFilterState state;
    Matrix15d covariance;
    ImuSample imu;
  };
  void Propagate(const ImuSample& previous, const ImuSample& imu, QuadFilterState* state,
                 Matrix15d* covariance) const;
  // Counts a refused step and returns its status.
  FilterStatus Refused(FilterStatus status);
  FilterStatus Correct(const VioSample& vio, QuadFilterState* state, Matrix15d* covariance);

  Params params_;
  QuadFilterConfig config_;
  QuadFilterState state_;
  Matrix15d covariance_;
  std::optional<ImuSample> last_imu_;
  RingQueue<Entry> history_;        // one entry per IMU sample, oldest first
  int consecutive_rejections_ = 0;  // VIO gate rejections in a row
  FilterCounts counts_;
};

}  // namespace hpa
