#include "hpa/estimator/support_detector.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

namespace hpa {

SupportDetector::SupportDetector(const Params& params, const SupportDetectorConfig& config)
    : config_(config), gravity_mps2_(params.gravity_mps2) {}

void SupportDetector::Clear() {
  head_ = 0;
  count_ = 0;
  supported_ = false;
  motion_valid_ = false;
  fit_start_s_ = -std::numeric_limits<double>::infinity();
  fit_a_WL_W_.setZero();
}

void SupportDetector::Add(double time_s, const Eigen::Vector3d& p_WL_W) {
  if (!std::isfinite(time_s) || !p_WL_W.allFinite()) return;
  if (count_ > 0 && time_s <= samples_[(head_ + count_ - 1) % kCapacity].time_s) return;
  // append (the oldest drops out when full), then drop what is older than the window
  if (count_ == kCapacity) {
    head_ = (head_ + 1) % kCapacity;
    --count_;
  }
  samples_[(head_ + count_) % kCapacity] = {time_s, p_WL_W};
  ++count_;
  while (count_ > 0 && samples_[head_].time_s < time_s - config_.window_s) {
    head_ = (head_ + 1) % kCapacity;
    --count_;
  }
  supported_ = false;
  motion_valid_ = false;
  if (count_ < config_.min_detections) return;
  // least squares p = a + b tau + c tau^2 per axis, tau = t - time_s (normal equations, 3 x 3;
  // the right-hand side's columns are the axes)
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d rhs = Eigen::Matrix3d::Zero();
  for (int i = 0; i < count_; ++i) {
    const Sample& s = samples_[(head_ + i) % kCapacity];
    const double tau = s.time_s - time_s;
    const Eigen::Vector3d row(1.0, tau, tau * tau);
    normal += row * row.transpose();
    rhs += row * s.p_WL_W.transpose();
  }
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(normal);
  const Eigen::Matrix3d coeffs = ldlt.solve(rhs);
  if (ldlt.info() != Eigen::Success || !coeffs.allFinite()) return;
  fit_time_s_ = time_s;
  fit_start_s_ = samples_[head_].time_s;
  fit_p_WL_W_ = coeffs.row(0).transpose();
  fit_v_WL_W_ = coeffs.row(1).transpose();
  fit_a_WL_W_ = 2.0 * coeffs.row(2).transpose();
  supported_ = fit_a_WL_W_.z() > -config_.fall_fraction * gravity_mps2_;
  double sum_sq_m2 = 0.0;
  for (int i = 0; i < count_; ++i) {
    const Sample& s = samples_[(head_ + i) % kCapacity];
    const double tau = s.time_s - time_s;
    const Eigen::Vector3d fitted = coeffs.transpose() * Eigen::Vector3d(1.0, tau, tau * tau);
    sum_sq_m2 += (s.p_WL_W - fitted).head<2>().squaredNorm();
  }
  motion_valid_ = std::sqrt(sum_sq_m2 / count_) <= config_.max_motion_residual_m;
}

bool SupportDetector::MotionAt(double time_s, Eigen::Vector3d* p_WL_W,
                               Eigen::Vector3d* v_WL_W) const {
  if (!motion_valid_) return false;
  const double age_s = std::clamp(time_s - fit_time_s_, 0.0, config_.max_extrapolation_s);
  *p_WL_W = fit_p_WL_W_ + fit_v_WL_W_ * age_s + 0.5 * fit_a_WL_W_ * age_s * age_s;
  *v_WL_W = fit_v_WL_W_ + fit_a_WL_W_ * age_s;
  return true;
}

}  // namespace hpa
