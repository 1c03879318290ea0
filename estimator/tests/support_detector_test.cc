#include "hpa/estimator/support_detector.h"

#include <gtest/gtest.h>

#include <random>

namespace hpa {
namespace {

// Heights at 30 Hz with the detector's noise (3 mm per axis, the rendered detector's error at
// the payload's depth is below that: docs/camera.md) along z(t).
template <typename Height>
SupportDetector Fed(const Height& z_of_t, int frames, uint64_t seed) {
  const Params p;
  SupportDetector detector(p, SupportDetectorConfig{});
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.003);
  for (int i = 0; i < frames; ++i) {
    const double t = i / 30.0;
    detector.Add(t, z_of_t(t) + noise(rng));
  }
  return detector;
}

TEST(SupportDetectorTest, TellsAHeldPayloadFromAFallingOrThrownOne) {
  const double g = Params().gravity_mps2;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    // held still, and carried up at 0.3 m/s by a hand
    EXPECT_TRUE(Fed([](double) { return 0.9; }, 10, seed).supported()) << seed;
    EXPECT_TRUE(Fed([](double t) { return 0.9 + 0.3 * t; }, 10, seed).supported()) << seed;
    // falling from rest, and thrown up at 3 m/s (rising, but decelerating at g)
    EXPECT_FALSE(Fed([g](double t) { return 0.9 - 0.5 * g * t * t; }, 10, seed).supported());
    EXPECT_FALSE(
        Fed([g](double t) { return 0.9 + 3.0 * t - 0.5 * g * t * t; }, 10, seed).supported());
    // the fitted acceleration: within 3 m/s^2 of the truth on six frames of 3 mm noise
    EXPECT_NEAR(Fed([g](double t) { return 1.0 - 0.5 * g * t * t; }, 10, seed).accel_z_mps2(), -g,
                3.0);
  }
}

TEST(SupportDetectorTest, SaysNothingOnTooFewDetectionsAndForgetsOnClear) {
  SupportDetector detector(Params(), SupportDetectorConfig{});
  for (int i = 0; i < 3; ++i) detector.Add(i / 30.0, 0.9);
  EXPECT_FALSE(detector.supported());  // three detections: no fit yet
  detector.Add(3 / 30.0, 0.9);
  EXPECT_TRUE(detector.supported());
  detector.Add(2 / 30.0, 0.0);  // out of order: ignored
  detector.Add(4 / 30.0, std::nan(""));
  EXPECT_TRUE(detector.supported());
  detector.Clear();
  EXPECT_FALSE(detector.supported());
  // a gap longer than the window leaves too few detections inside it
  for (int i = 0; i < 3; ++i) detector.Add(10.0 + i / 30.0, 0.9);
  EXPECT_FALSE(detector.supported());
}

}  // namespace
}  // namespace hpa
