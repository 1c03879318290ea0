#include "hpa/estimator/mode_detector.h"

#include <cmath>

namespace hpa {

ModeDetector::ModeDetector(const Params& params, const ModeDetectorConfig& config,
                           CableMode initial, double initial_length_m)
    : config_(config),
      threshold_m_(params.cable_length_m - params.slack_epsilon_m),
      mode_(initial),
      filtered_length_m_(initial_length_m) {}

CableMode ModeDetector::Update(double time_s, double cable_length_m) {
  if (!std::isfinite(time_s) || !std::isfinite(cable_length_m)) return mode_;
  if (started_ && time_s <= last_time_s_) return mode_;
  // first-order low pass with the actual sample spacing (a missed frame weighs more)
  const double alpha =
      started_ ? 1.0 - std::exp(-(time_s - last_time_s_) / config_.filter_time_constant_s) : 1.0;
  filtered_length_m_ += alpha * (cable_length_m - filtered_length_m_);
  started_ = true;
  last_time_s_ = time_s;
  mode_ = filtered_length_m_ < threshold_m_ ? CableMode::kSlack : CableMode::kTaut;
  return mode_;
}

}  // namespace hpa
