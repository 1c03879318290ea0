#include "hpa/estimator/cable_ekf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "hpa/models/hybrid_model.h"
#include "hpa/models/rotor_model.h"

namespace hpa {
namespace {

double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / M_PI;
}

// Swinging payload under a level quadrotor at hover thrust, simulated with the analytic taut
// model; body-frame payload measurements at 30 Hz with 3 mm noise arrive one frame late.
struct SwingRun {
  double final_angle_error_deg = 0.0;
  double final_rate_error_per_s = 0.0;
  double max_angle_error_after_1s_deg = 0.0;
};

SwingRun RunSwing(const Eigen::Vector3d& xi0_ekf, double blackout_start_s, double blackout_end_s,
                  uint64_t seed) {
  const Params p;
  const HybridModel model(p);
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0, 0, 1.5);
  const Eigen::Vector3d xi0 = Eigen::Vector3d(std::sin(0.35), 0.1, -std::cos(0.35)).normalized();
  s.p_WL_W = s.p_WQ_W + p.cable_length_m * xi0;
  StateVector x = s.ToVector();
  const InputVector u = InputVector::Constant(p.HoverMotorSpeedRadps());
  const double thrust_N = WrenchFromRotorSpeeds(p, u)(0);

  CableEkf ekf(p, CableEkfConfig{}, xi0_ekf, Eigen::Vector3d::Zero(), 0.0);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.003);
  const Eigen::Matrix3d cov_B = Eigen::Matrix3d::Identity() * 0.003 * 0.003;
  constexpr double kDt = 0.002;
  struct Pending {
    double t;
    Eigen::Vector3d p_BL_B;
    Eigen::Matrix3d R_WB;
  };
  std::vector<Pending> pending;
  SwingRun run;
  for (int k = 1; k <= 1500; ++k) {  // 3 s
    x = model.Step(x, u, CableMode::kTaut, kDt);
    const double t = k * kDt;
    s.FromVector(x);
    const Eigen::Matrix3d R_WB = s.q_WB.toRotationMatrix();
    EXPECT_EQ(ekf.Predict(t, thrust_N, R_WB), FilterStatus::kOk);
    // camera frame every 1/30 s, delivered one frame later
    if (k % 17 == 0) {
      for (const Pending& m : pending) ekf.Update(m.t, m.p_BL_B, m.R_WB, cov_B);
      pending.clear();
      if (t < blackout_start_s || t > blackout_end_s) {
        const Eigen::Vector3d n(noise(rng), noise(rng), noise(rng));
        pending.push_back({t, R_WB.transpose() * (s.p_WL_W - s.p_WQ_W) + n, R_WB});
      }
    }
    const Eigen::Vector3d xi = (s.p_WL_W - s.p_WQ_W).normalized();
    // the constraint holds after every step
    EXPECT_NEAR(ekf.xi_W().norm(), 1.0, 1e-12);
    EXPECT_NEAR(ekf.xi_W().dot(ekf.xi_dot_W()), 0.0, 1e-12);
    if (t > 1.0) {
      run.max_angle_error_after_1s_deg =
          std::max(run.max_angle_error_after_1s_deg, AngleDeg(ekf.xi_W(), xi));
    }
    if (k == 1500) {
      const Eigen::Vector3d xi_dot = (s.v_WL_W - s.v_WQ_W) / p.cable_length_m;
      run.final_angle_error_deg = AngleDeg(ekf.xi_W(), xi);
      run.final_rate_error_per_s = (ekf.xi_dot_W() - xi_dot).norm();
    }
  }
  return run;
}

TEST(CableEkfTest, ConvergesFromAWrongInitialDirection) {
  // truth swings 20 deg off vertical toward +x; the filter starts 45 deg off toward -y
  const Eigen::Vector3d wrong = Eigen::Vector3d(0, -std::sin(0.8), -std::cos(0.8));
  const SwingRun run = RunSwing(wrong, 1e9, 1e9, 3);
  std::printf(
      "cable EKF from 45 deg off: max angle error after 1 s %.2f deg, final %.2f deg, "
      "final rate error %.3f 1/s\n",
      run.max_angle_error_after_1s_deg, run.final_angle_error_deg, run.final_rate_error_per_s);
  // 3 mm noise on a 0.5 m cable is 0.34 deg per frame and axis. Measured (seed 3): max 1.6 deg
  // after 1 s, 0.07 1/s at the end; bounds ~2x: 3 deg (15x below the initial 45 deg) and
  // 0.2 1/s (the pendulum's rate amplitude is ~1.8 1/s)
  EXPECT_LT(run.max_angle_error_after_1s_deg, 3.0);
  EXPECT_LT(run.final_rate_error_per_s, 0.2);
}

TEST(CableEkfTest, PredictsThroughMissedDetections) {
  // no detections between 1.5 s and 2.0 s (15 frames): the process model carries the swing
  const Eigen::Vector3d start = Eigen::Vector3d(0, 0, -1);
  const SwingRun with_gap = RunSwing(start, 1.5, 2.0, 4);
  std::printf("cable EKF with a 0.5 s detection gap: max angle error after 1 s %.2f deg\n",
              with_gap.max_angle_error_after_1s_deg);
  // the exact process model (same thrust and attitude as the truth) drifts only with the
  // state error at the start of the gap; measured 1.6 deg (seed 4), bound 3 deg as above
  EXPECT_LT(with_gap.max_angle_error_after_1s_deg, 3.0);
}

TEST(CableEkfTest, HangingPayloadUnderHoverThrustStaysPut) {
  const Params p;
  CableEkf ekf(p, CableEkfConfig{}, Eigen::Vector3d(0, 0, -1), Eigen::Vector3d::Zero(), 0.0);
  for (int k = 1; k <= 500; ++k)
    ekf.Predict(k * 0.002, p.HoverThrustN(), Eigen::Matrix3d::Identity());
  // xi x (xi x e3) = 0 for xi = -e3: an equilibrium, rounding only
  EXPECT_LT((ekf.xi_W() - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
}

TEST(CableEkfTest, WildDetectionIsRejectedUntilTheRunForcesAnAccept) {
  // hanging payload; detections put it 0.5 m to the side (90 deg off): far outside the gate
  const Params p;
  const CableEkfConfig config;
  CableEkf ekf(p, config, Eigen::Vector3d(0, 0, -1), Eigen::Vector3d::Zero(), 0.0);
  const Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d cov_B = Eigen::Matrix3d::Identity() * 1e-5;
  double t = 0.0;
  for (int k = 0; k < 50; ++k)
    ASSERT_EQ(ekf.Predict(t += 0.002, p.HoverThrustN(), R), FilterStatus::kOk);
  // a detection where the filter expects the payload passes
  EXPECT_EQ(ekf.Update(t, Eigen::Vector3d(0, 0, -0.5), R, cov_B), FilterStatus::kOk);
  EXPECT_LT(ekf.counts().last_nis, config.gate.nis_threshold);
  const Eigen::Vector3d wild_B(0.5, 0, 0);
  for (int k = 1; k <= config.gate.max_consecutive_rejections; ++k) {
    ASSERT_EQ(ekf.Predict(t += 0.002, p.HoverThrustN(), R), FilterStatus::kOk);
    EXPECT_EQ(ekf.Update(t, wild_B, R, cov_B), FilterStatus::kRejected) << "detection " << k;
    EXPECT_GT(ekf.counts().last_nis, config.gate.nis_threshold);
    EXPECT_LT((ekf.xi_W() - Eigen::Vector3d(0, 0, -1)).norm(), 1e-9);  // rejected: untouched
  }
  EXPECT_EQ(ekf.counts().rejected_updates, config.gate.max_consecutive_rejections);
  EXPECT_EQ(ekf.counts().forced_accepts, 0);
  // the next one in the run is fused: the filter is then assumed wrong, not the camera
  ASSERT_EQ(ekf.Predict(t += 0.002, p.HoverThrustN(), R), FilterStatus::kOk);
  EXPECT_EQ(ekf.Update(t, wild_B, R, cov_B), FilterStatus::kOk);
  EXPECT_EQ(ekf.counts().forced_accepts, 1);
  EXPECT_EQ(ekf.counts().accepted_updates, 2);
  EXPECT_GT(ekf.xi_W().x(), 0.5);  // pulled toward +x: measured 0.96, bound half of it
  EXPECT_NEAR(ekf.xi_W().norm(), 1.0, 1e-12);
}

TEST(CableEkfTest, NonFiniteAndStaleInputsAreIgnored) {
  const Params p;
  CableEkf ekf(p, CableEkfConfig{}, Eigen::Vector3d(0, 0, -1), Eigen::Vector3d::Zero(), 1.0);
  EXPECT_EQ(ekf.Predict(1.002, std::nan(""), Eigen::Matrix3d::Identity()),
            FilterStatus::kNonFinite);
  EXPECT_EQ(ekf.Predict(0.5, 1.0, Eigen::Matrix3d::Identity()), FilterStatus::kOutOfOrder);
  EXPECT_EQ(ekf.Update(0.2, Eigen::Vector3d(0, 0, 0.5), Eigen::Matrix3d::Identity(),
                       Eigen::Matrix3d::Identity() * 1e-5),
            FilterStatus::kTooOld);
  EXPECT_EQ(ekf.Update(1.0, Eigen::Vector3d(0, INFINITY, 0.5), Eigen::Matrix3d::Identity(),
                       Eigen::Matrix3d::Identity() * 1e-5),
            FilterStatus::kNonFinite);
  EXPECT_TRUE(ekf.xi_W().allFinite());
  EXPECT_EQ(ekf.xi_W(), Eigen::Vector3d(0, 0, -1));
  EXPECT_EQ(ekf.counts().non_finite, 2);
  EXPECT_EQ(ekf.counts().out_of_order, 1);
  EXPECT_EQ(ekf.counts().too_old, 1);
  EXPECT_EQ(ekf.counts().accepted_updates, 0);
}

}  // namespace
}  // namespace hpa
