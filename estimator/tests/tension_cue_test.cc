#include "hpa/estimator/tension_cue.h"

#include <gtest/gtest.h>

#include <cmath>

namespace hpa {
namespace {

constexpr double kImuDt_s = 0.002;  // 500 Hz IMU

// Feeds `samples` IMU samples of a level vehicle at rest under thrust_N, the cable hanging
// straight down, whose accelerometer reads `accel_z_mps2`; returns the time of the first sample
// that read slack (or -1).
double Feed(TensionCue* cue, double t0_s, int samples, double accel_z_mps2, double thrust_N) {
  double first_slack_s = -1.0;
  for (int k = 1; k <= samples; ++k) {
    const double t = t0_s + k * kImuDt_s;
    if (cue->Update(t, Eigen::Vector3d(0, 0, accel_z_mps2), Eigen::Matrix3d::Identity(), thrust_N,
                    Eigen::Vector3d(0, 0, -1)) &&
        first_slack_s < 0) {
      first_slack_s = t;
    }
  }
  return first_slack_s;
}

TEST(TensionCueTest, AHangingPayloadReadsTautAtItsWeight) {
  const Params p;
  TensionCue cue(p, TensionCueConfig{}, /*start_slack=*/false);
  const double thrust_N = (p.quad_mass_kg + p.payload_mass_kg) * p.gravity_mps2;
  // at rest: the accelerometer reads g; the cable carries the rest of the thrust
  EXPECT_LT(Feed(&cue, 0.0, 250, p.gravity_mps2, thrust_N), 0.0);
  EXPECT_FALSE(cue.slack());
  EXPECT_NEAR(cue.tension_N(), p.payload_mass_kg * p.gravity_mps2, 1e-6);
}

TEST(TensionCueTest, AnUnloadedCableReadsSlackWithinTheFilterTime) {
  const Params p;
  const TensionCueConfig config;
  TensionCue cue(p, config, false);
  const double thrust_N = (p.quad_mass_kg + p.payload_mass_kg) * p.gravity_mps2;
  Feed(&cue, 0.0, 100, p.gravity_mps2, thrust_N);
  // the payload is taken at t = 0.2 s: the same thrust now accelerates the vehicle alone
  const double slack_s = Feed(&cue, 0.2, 100, thrust_N / p.quad_mass_kg, thrust_N);
  // tension falls as exp(-t / tau) from m_L g: below 0.25 m_L g after tau ln 4 = 27.7 ms
  const double expected_s = config.filter_time_constant_s * std::log(1.0 / config.slack_fraction);
  ASSERT_GT(slack_s, 0.0) << "never read slack";
  EXPECT_NEAR(slack_s - 0.2, expected_s, 2 * kImuDt_s);
}

TEST(TensionCueTest, HysteresisHoldsBetweenTheTwoFractions) {
  const Params p;
  const double weight_N = p.payload_mass_kg * p.gravity_mps2;
  // a tension of 0.4 m_L g (between 0.25 and 0.5): whichever the cue read, it keeps
  const double accel = p.gravity_mps2 + 0.6 * weight_N / p.quad_mass_kg;
  const double thrust_N = p.quad_mass_kg * p.gravity_mps2 + weight_N;
  for (const bool start_slack : {false, true}) {
    TensionCue cue(p, TensionCueConfig{}, start_slack);
    Feed(&cue, 0.0, 500, accel, thrust_N);
    EXPECT_NEAR(cue.tension_N(), 0.4 * weight_N, 1e-6);
    EXPECT_EQ(cue.slack(), start_slack);
  }
}

TEST(TensionCueTest, NonFiniteOrOutOfOrderInputChangesNothing) {
  const Params p;
  TensionCue cue(p, TensionCueConfig{}, false);
  const double thrust_N = (p.quad_mass_kg + p.payload_mass_kg) * p.gravity_mps2;
  Feed(&cue, 0.0, 50, p.gravity_mps2, thrust_N);
  const double before_N = cue.tension_N();
  EXPECT_FALSE(cue.Update(1.0, Eigen::Vector3d(0, 0, NAN), Eigen::Matrix3d::Identity(), thrust_N,
                          Eigen::Vector3d(0, 0, -1)));
  EXPECT_FALSE(cue.Update(1.0, Eigen::Vector3d(0, 0, 20.0), Eigen::Matrix3d::Identity(), INFINITY,
                          Eigen::Vector3d(0, 0, -1)));
  // a sample older than the last one
  EXPECT_FALSE(cue.Update(0.05, Eigen::Vector3d(0, 0, 30.0), Eigen::Matrix3d::Identity(), thrust_N,
                          Eigen::Vector3d(0, 0, -1)));
  EXPECT_EQ(cue.tension_N(), before_N);
}

}  // namespace
}  // namespace hpa
