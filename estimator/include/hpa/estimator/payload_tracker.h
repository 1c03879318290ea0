#pragma once
// Payload tracker for slack phases: a linear Kalman filter on the payload's world position and
// velocity with free fall between detections (paper eq. 10: m_L (a_L + g e3) = 0).

#include <Eigen/Core>
#include <limits>

#include "hpa/estimator/filter_status.h"
#include "hpa/models/params.h"

namespace hpa {

/// Tuning of the payload tracker.
struct PayloadTrackerConfig {
  double accel_noise_mps2_per_sqrts = 1.0;  // unmodelled acceleration (air drag, cable tug)
  // detection gate; off by default (every detection is fused), 3 dof when set
  InnovationGate gate = {std::numeric_limits<double>::infinity(), 0};
};

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// State [p_WL_W, v_WL_W]; predicts in free fall, updates with world-frame detections.
class PayloadTracker {
 public:
  PayloadTracker(const Params& params, const PayloadTrackerConfig& config);

  /// Restarts at time_s (the gate's run of rejections too) from position, velocity and their 6x6
  /// covariance.
  void Reset(double time_s, const Eigen::Vector3d& p_WL_W, const Eigen::Vector3d& v_WL_W,
             const Matrix6d& covariance);

  /// Predicts in free fall to time_s, then fuses the measured position (covariance cov_W_m2)
  /// through the gate. A measurement older than the tracker's time is applied at the tracker's
  /// time. The prediction stays even when the gate rejects the measurement.
  FilterStatus Update(double time_s, const Eigen::Vector3d& p_WL_W,
                      const Eigen::Matrix3d& cov_W_m2);

  /// Free-fall extrapolation to time_s (no change of the filter).
  void PredictTo(double time_s, Eigen::Vector3d* p_WL_W, Eigen::Vector3d* v_WL_W) const;

  double time_s() const { return time_s_; }
  const Vector6d& state() const { return x_; }
  const Matrix6d& covariance() const { return covariance_; }
  /// Counts of accepted, rejected, forced and refused updates.
  const FilterCounts& counts() const { return counts_; }

 private:
  Params params_;
  PayloadTrackerConfig config_;
  double time_s_ = 0.0;
  Vector6d x_ = Vector6d::Zero();
  Matrix6d covariance_ = Matrix6d::Identity();
  int consecutive_rejections_ = 0;  // gate rejections in a row
  FilterCounts counts_;
};

}  // namespace hpa
