#include "hpa/autopilot/butterworth_low_pass.h"

#include <gtest/gtest.h>

#include <cmath>

namespace hpa {
namespace {

TEST(ButterworthLowPassTest, FirstSampleIsTheSteadyState) {
  ButterworthLowPass f(1000.0, 30.0);
  const Eigen::Vector3d x(0.3, -2.0, 5.0);
  // a constant input stays constant from the first sample on (1e-12: rounding of a biquad)
  for (int k = 0; k < 10; ++k) EXPECT_TRUE((f.Apply(x) - x).isZero(1e-12));
}

TEST(ButterworthLowPassTest, GainAtCutoffIsMinus3dB) {
  // a sine at the cutoff, after the transient: amplitude 1/sqrt(2) (the bilinear transform with
  // pre-warping puts the -3 dB point exactly at the cutoff; 1e-3: the peak of a sampled sine
  // falls between samples by at most 1 - cos(pi fc / fs) = 4e-3 of it, measured 2e-4 here)
  const double fs = 1000.0, fc = 30.0;
  ButterworthLowPass f(fs, fc);
  f.Reset(Eigen::Vector3d::Zero());
  double peak = 0.0;
  for (int k = 0; k < 4000; ++k) {
    const double y = f.Apply(Eigen::Vector3d::Constant(std::sin(2 * M_PI * fc * k / fs)))(0);
    if (k > 2000) peak = std::max(peak, std::abs(y));
  }
  EXPECT_NEAR(peak, 1.0 / std::sqrt(2.0), 1e-3);
}

TEST(ButterworthLowPassTest, ZeroCutoffPassesThrough) {
  ButterworthLowPass f(1000.0, 0.0);  // PX4: 0 disables the filter
  EXPECT_TRUE(f.pass_through());
  f.Apply(Eigen::Vector3d::Zero());
  EXPECT_EQ(f.Apply(Eigen::Vector3d(1, 2, 3)), Eigen::Vector3d(1, 2, 3));
  // at or above Nyquist the filter cannot be built: pass-through as well
  EXPECT_TRUE(ButterworthLowPass(1000.0, 500.0).pass_through());
}

}  // namespace
}  // namespace hpa
