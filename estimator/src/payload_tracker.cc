#include "hpa/estimator/payload_tracker.h"

#include <Eigen/Cholesky>
#include <cmath>

#include "gated_update.h"

namespace hpa {

PayloadTracker::PayloadTracker(const Params& params, const PayloadTrackerConfig& config)
    : params_(params), config_(config) {}

void PayloadTracker::Reset(double time_s, const Eigen::Vector3d& p_WL_W,
                           const Eigen::Vector3d& v_WL_W, const Matrix6d& covariance) {
  time_s_ = time_s;
  x_ << p_WL_W, v_WL_W;
  covariance_ = covariance;
  consecutive_rejections_ = 0;
}

void PayloadTracker::PredictTo(double time_s, Eigen::Vector3d* p_WL_W,
                               Eigen::Vector3d* v_WL_W) const {
  const double dt_s = std::max(0.0, time_s - time_s_);
  const Eigen::Vector3d g_W(0, 0, -params_.gravity_mps2);
  *p_WL_W = x_.head<3>() + x_.tail<3>() * dt_s + 0.5 * g_W * dt_s * dt_s;
  *v_WL_W = x_.tail<3>() + g_W * dt_s;
}

FilterStatus PayloadTracker::Update(double time_s, const Eigen::Vector3d& p_WL_W,
                                    const Eigen::Matrix3d& cov_W_m2) {
  if (!std::isfinite(time_s) || !p_WL_W.allFinite() || !cov_W_m2.allFinite()) {
    counts_.CountRefused(FilterStatus::kNonFinite);
    return FilterStatus::kNonFinite;
  }
  // free-fall prediction with white-acceleration process noise
  const double dt_s = std::max(0.0, time_s - time_s_);
  Eigen::Vector3d p, v;
  PredictTo(time_s, &p, &v);
  x_ << p, v;
  Matrix6d F = Matrix6d::Identity();
  F.block<3, 3>(0, 3) = Eigen::Matrix3d::Identity() * dt_s;
  const double q = std::pow(config_.accel_noise_mps2_per_sqrts, 2);
  Matrix6d Q = Matrix6d::Zero();
  Q.block<3, 3>(0, 0).diagonal().setConstant(q * dt_s * dt_s * dt_s / 3.0);
  Q.block<3, 3>(0, 3).diagonal().setConstant(q * dt_s * dt_s / 2.0);
  Q.block<3, 3>(3, 0).diagonal().setConstant(q * dt_s * dt_s / 2.0);
  Q.block<3, 3>(3, 3).diagonal().setConstant(q * dt_s);
  covariance_ = F * covariance_ * F.transpose() + Q;
  time_s_ = std::max(time_s_, time_s);

  // position measurement, H = [I 0]
  const Eigen::Vector3d r = p_WL_W - x_.head<3>();
  Eigen::Matrix<double, 3, 6> H = Eigen::Matrix<double, 3, 6>::Zero();
  H.leftCols<3>().setIdentity();
  const GatedUpdateResult<6> update =
      GatedKalmanUpdate<6, 3>(r, H, cov_W_m2, config_.gate, GainProduct::kHP,
                              &consecutive_rejections_, &covariance_, &counts_);
  if (update.status != FilterStatus::kOk) return update.status;
  x_ += update.dx;
  return FilterStatus::kOk;
}

}  // namespace hpa
