#include "hpa/autopilot/butterworth_low_pass.h"

#include <cmath>

namespace hpa {

ButterworthLowPass::ButterworthLowPass(double sample_hz, double cutoff_hz) {
  if (!(sample_hz > 0.0) || !(cutoff_hz > 0.0) || !(cutoff_hz < 0.5 * sample_hz)) return;
  pass_through_ = false;
  // analog prototype s^2 + 2 cos(pi/4) s + 1, pre-warped cutoff tan(pi fc / fs)
  const double ohm = std::tan(M_PI * cutoff_hz / sample_hz);
  const double c = 1.0 + 2.0 * std::cos(M_PI / 4.0) * ohm + ohm * ohm;
  b0_ = ohm * ohm / c;
  b1_ = 2.0 * b0_;
  b2_ = b0_;
  a1_ = 2.0 * (ohm * ohm - 1.0) / c;
  a2_ = (1.0 - 2.0 * std::cos(M_PI / 4.0) * ohm + ohm * ohm) / c;
}

void ButterworthLowPass::Reset(const Eigen::Vector3d& sample) {
  initialised_ = true;
  if (pass_through_) return;
  // w[n] = x - a1 w[n-1] - a2 w[n-2] constant: w = x / (1 + a1 + a2); output (b0+b1+b2) w = x
  delay1_ = sample / (1.0 + a1_ + a2_);
  delay2_ = delay1_;
}

Eigen::Vector3d ButterworthLowPass::Apply(const Eigen::Vector3d& sample) {
  if (!initialised_) Reset(sample);
  if (pass_through_) return sample;
  const Eigen::Vector3d w = sample - a1_ * delay1_ - a2_ * delay2_;
  const Eigen::Vector3d out = b0_ * w + b1_ * delay1_ + b2_ * delay2_;
  delay2_ = delay1_;
  delay1_ = w;
  return out;
}

}  // namespace hpa
