// The analytic camera (sim) against the real detector (flight code) on synthetic frames: the
// cross-check lives with the scenarios, the only layer that links both.
#include "hpa/sim/analytic_camera.h"

#include <gtest/gtest.h>

#include <random>

#include "hpa/estimator/payload_detector.h"
#include "hpa/models/camera_model.h"
#include "estimator/tests/synthetic_frames.h"

namespace hpa {
namespace {

TEST(AnalyticCameraTest, NoiselessMeasurementIsExact) {
  const Params p;
  const sim::AnalyticCamera camera(p, CameraNoiseModel{0.0, 0.0, 0.0, 0.0});
  std::mt19937_64 rng(1);
  for (const Eigen::Vector3d& p_CL_C :
       {Eigen::Vector3d(0, 0, 0.45), Eigen::Vector3d(0.25, -0.12, 0.4),
        Eigen::Vector3d(-0.3, 0.15, 0.5)}) {
    const PayloadDetection d = camera.Measure(p_CL_C, 2.0, rng);
    ASSERT_TRUE(d.found) << d.reason;
    // exact ellipse geometry and back-projection: rounding only
    EXPECT_LT((d.p_CL_C - p_CL_C).norm(), 1e-9);
    EXPECT_DOUBLE_EQ(d.time_s, 2.0);
  }
}

TEST(AnalyticCameraTest, AgreesWithTheDetectorOnVisibility) {
  // the same acceptance rule as the detector: compare on synthetic frames across the edge
  const Params p;
  const sim::AnalyticCamera camera(p);
  const PayloadDetector detector(p);
  std::mt19937_64 rng(2);
  const double z = 0.45;
  int agree = 0, total = 0;
  for (double inset_px : {-60.0, -20.0, 0.0, 20.0, 45.0, 80.0, 150.0}) {
    const double x = (0.5 * p.camera_width_px - inset_px) / p.CameraFocalPx() * z;
    const Eigen::Vector3d p_CL_C(x, 0.01, z);
    const bool analytic = camera.Measure(p_CL_C, 0.0, rng).found;
    const bool rendered = detector.Detect(testing_frames::RenderSphere(p, p_CL_C), 0.0).found;
    agree += analytic == rendered;
    ++total;
  }
  // the threshold case can differ by one position (the fitted and the exact outline differ)
  EXPECT_GE(agree, total - 1);
}

TEST(AnalyticCameraTest, NoiseMatchesTheModelledCovariance) {
  const Params p;
  const CameraNoiseModel noise = MeasuredDetectorNoise();
  const sim::AnalyticCamera camera(p, noise);
  std::mt19937_64 rng(3);
  const Eigen::Vector3d p_CL_C(0.1, 0.05, 0.45);
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  constexpr int kSamples = 20000;
  for (int i = 0; i < kSamples; ++i) {
    const Eigen::Vector3d e = camera.Measure(p_CL_C, 0.0, rng).p_CL_C - p_CL_C;
    scatter += e * e.transpose();
  }
  scatter /= kSamples;
  const Eigen::Matrix3d model = DetectionCovariance_C(p, noise, p_CL_C);
  // first-order covariance vs sampled: 20000 samples give ~1% sampling error on a variance;
  // linearisation adds little at sub-pixel noise. Bound: 10% of the largest variance
  EXPECT_LT((scatter - model).cwiseAbs().maxCoeff(), 0.1 * model.diagonal().maxCoeff());
}

TEST(AnalyticCameraTest, OutOfViewAndBehindAreNotFound) {
  const Params p;
  const sim::AnalyticCamera camera(p);
  std::mt19937_64 rng(4);
  EXPECT_FALSE(camera.Measure(Eigen::Vector3d(0, 0, -0.4), 0.0, rng).found);
  EXPECT_FALSE(camera.Measure(Eigen::Vector3d(2.0, 0, 0.4), 0.0, rng).found);
  EXPECT_EQ(camera.Measure(Eigen::Vector3d(0, 0, 5.0), 0.0, rng).reason, "too small");
}

}  // namespace
}  // namespace hpa
