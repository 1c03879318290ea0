#include "hpa/estimator/support_detector.h"

#include <Eigen/Dense>
#include <cmath>

namespace hpa {

SupportDetector::SupportDetector(const Params& params, const SupportDetectorConfig& config)
    : config_(config), gravity_mps2_(params.gravity_mps2) {}

void SupportDetector::Clear() {
  head_ = 0;
  count_ = 0;
  supported_ = false;
  accel_z_mps2_ = 0.0;
}

void SupportDetector::Add(double time_s, double z_W_m) {
  if (!std::isfinite(time_s) || !std::isfinite(z_W_m)) return;
  if (count_ > 0 && time_s <= samples_[(head_ + count_ - 1) % kCapacity].time_s) return;
  // append (the oldest drops out when full), then drop what is older than the window
  if (count_ == kCapacity) {
    head_ = (head_ + 1) % kCapacity;
    --count_;
  }
  samples_[(head_ + count_) % kCapacity] = {time_s, z_W_m};
  ++count_;
  while (count_ > 0 && samples_[head_].time_s < time_s - config_.window_s) {
    head_ = (head_ + 1) % kCapacity;
    --count_;
  }
  if (count_ < config_.min_detections) {
    supported_ = false;
    return;
  }
  // least squares z = a + b tau + c tau^2, tau = t - time_s (normal equations, 3 x 3)
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (int i = 0; i < count_; ++i) {
    const Sample& s = samples_[(head_ + i) % kCapacity];
    const double tau = s.time_s - time_s;
    const Eigen::Vector3d row(1.0, tau, tau * tau);
    normal += row * row.transpose();
    rhs += row * s.z_W_m;
  }
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(normal);
  const Eigen::Vector3d coeffs = ldlt.solve(rhs);
  if (ldlt.info() != Eigen::Success || !coeffs.allFinite()) {
    supported_ = false;
    return;
  }
  accel_z_mps2_ = 2.0 * coeffs(2);
  supported_ = accel_z_mps2_ > -config_.fall_fraction * gravity_mps2_;
}

}  // namespace hpa
