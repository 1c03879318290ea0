#include "hpa/autopilot/body_rate_controller.h"

#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "hpa/models/rotor_model.h"

namespace hpa {
namespace {

constexpr double kDtS = 0.002;  // 500 Hz

TEST(BodyRateControllerTest, HoverCommandGivesEqualHoverSpeeds) {
  const Params params;
  BodyRateController c(params);
  BodyRateCommand cmd;
  cmd.thrust_N = params.HoverThrustN();
  const InputVector w = c.Update(cmd, Eigen::Vector3d::Zero(), kDtS);
  // 1e-9 relative: one 4x4 inverse and a square root
  EXPECT_TRUE(w.isApprox(InputVector::Constant(params.HoverMotorSpeedRadps()), 1e-9));
  EXPECT_FALSE(c.status().saturated);
}

TEST(BodyRateControllerTest, MomentSignsFollowRateErrors) {
  const Params params;
  for (int axis = 0; axis < 3; ++axis) {
    BodyRateController c(params);
    BodyRateCommand cmd;
    cmd.thrust_N = params.HoverThrustN();
    cmd.w_B_radps(axis) = 1.0;
    const Eigen::Vector4d wrench = WrenchFromRotorSpeeds(params, c.Update(cmd, {0, 0, 0}, kDtS));
    // the commanded axis gets a positive moment J kp e, the others none (1e-9 N m: rounding)
    const BodyRateGains gains;
    EXPECT_NEAR(wrench(1 + axis), params.inertia_B_kgm2(axis) * gains.kp_per_s(axis), 1e-9);
    for (int other = 0; other < 3; ++other) {
      if (other != axis) {
        EXPECT_NEAR(wrench(1 + other), 0.0, 1e-9);
      }
    }
    EXPECT_NEAR(wrench(0), params.HoverThrustN(), 1e-9);
  }
}

TEST(BodyRateControllerTest, GyroscopicFeedForward) {
  const Params params;
  BodyRateController c(params);
  BodyRateCommand cmd;
  cmd.thrust_N = params.HoverThrustN();
  const Eigen::Vector3d w(2.0, -1.0, 3.0);
  cmd.w_B_radps = w;  // no error: moment is w x J w only
  const Eigen::Vector4d wrench = WrenchFromRotorSpeeds(params, c.Update(cmd, w, kDtS));
  const Eigen::Vector3d expected = w.cross(params.inertia_B_kgm2.cwiseProduct(w));
  EXPECT_TRUE((wrench.tail<3>() - expected).isZero(1e-9));
}

TEST(BodyRateControllerTest, SaturationKeepsThrustAndScalesMomentInClosedForm) {
  const Params params;
  const double f_max = params.k_f_N_per_radps2 * std::pow(params.motor_speed_max_radps, 2);
  const double f_min = params.k_f_N_per_radps2 * std::pow(params.motor_speed_min_radps, 2);
  const double d = params.arm_length_m / std::sqrt(2.0);  // rotor y offset
  const double thrust = params.HoverThrustN();
  const double m_x = 2.0;  // N m, far beyond what the rotors can give at hover thrust
  // pure roll: rotors 0, 1 get f/4 + M/(4 d), rotors 2, 3 get f/4 - M/(4 d)
  const double alpha_expected = std::min(f_max - thrust / 4, thrust / 4 - f_min) / (m_x / (4 * d));
  double alpha = -1.0;
  const InputVector w = BodyRateController::AllocateWithThrustPriority(
      params, Eigen::Vector4d(thrust, m_x, 0, 0), &alpha);
  EXPECT_NEAR(alpha, alpha_expected, 1e-12);
  const Eigen::Vector4d wrench = WrenchFromRotorSpeeds(params, w);
  EXPECT_NEAR(wrench(0), thrust, 1e-9);                // thrust kept exactly
  EXPECT_NEAR(wrench(1), alpha_expected * m_x, 1e-9);  // moment scaled
  EXPECT_NEAR(wrench(2), 0.0, 1e-9);
  // the binding rotor sits on its bound
  EXPECT_NEAR(std::max(w.maxCoeff() - params.motor_speed_max_radps,
                       params.motor_speed_min_radps - w.minCoeff()),
              0.0, 1e-6);

  // full thrust: no room for any moment, all rotors at maximum
  const InputVector w_full = BodyRateController::AllocateWithThrustPriority(
      params, Eigen::Vector4d(10 * f_max, 0.1, 0, 0), &alpha);
  EXPECT_EQ(alpha, 0.0);
  EXPECT_TRUE(w_full.isApprox(InputVector::Constant(params.motor_speed_max_radps), 1e-12));
}

TEST(BodyRateControllerTest, RandomCommandsStayInsideMotorBounds) {
  const Params params;
  BodyRateController c(params);
  std::mt19937 rng(42);
  std::normal_distribution<double> rate(0.0, 10.0);
  std::uniform_real_distribution<double> thrust(-5.0, 30.0);
  for (int i = 0; i < 1000; ++i) {
    BodyRateCommand cmd;
    cmd.w_B_radps = Eigen::Vector3d(rate(rng), rate(rng), rate(rng));
    cmd.thrust_N = thrust(rng);
    const InputVector w = c.Update(cmd, Eigen::Vector3d(rate(rng), rate(rng), rate(rng)), kDtS);
    ASSERT_TRUE(w.allFinite());
    EXPECT_GE(w.minCoeff(), params.motor_speed_min_radps);
    EXPECT_LE(w.maxCoeff(), params.motor_speed_max_radps);
  }
}

TEST(BodyRateControllerTest, RejectsNonFiniteInputWithSafeOutput) {
  const Params params;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const InputVector hover = InputVector::Constant(params.HoverMotorSpeedRadps());
  BodyRateController c(params);
  BodyRateCommand cmd;
  cmd.thrust_N = params.HoverThrustN();
  cmd.w_B_radps = Eigen::Vector3d(nan, 0, 0);
  EXPECT_TRUE(c.Update(cmd, Eigen::Vector3d::Zero(), kDtS).isApprox(hover, 1e-9));
  EXPECT_FALSE(c.status().input_valid);
  cmd.w_B_radps.setZero();
  cmd.thrust_N = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(c.Update(cmd, Eigen::Vector3d::Zero(), kDtS).isApprox(hover, 1e-9));
  cmd.thrust_N = params.HoverThrustN();
  EXPECT_TRUE(c.Update(cmd, Eigen::Vector3d(0, nan, 0), kDtS).isApprox(hover, 1e-9));
  EXPECT_TRUE(c.Update(cmd, Eigen::Vector3d::Zero(), nan).isApprox(hover, 1e-9));
  // and recovers on valid input
  c.Update(cmd, Eigen::Vector3d::Zero(), kDtS);
  EXPECT_TRUE(c.status().input_valid);
}

TEST(BodyRateControllerTest, IntegratorRemovesSteadyDisturbance) {
  // single-axis plant J w_dot = M - M_dist; the integral term must cancel M_dist
  const Params params;
  BodyRateController c(params);
  BodyRateCommand cmd;
  cmd.thrust_N = params.HoverThrustN();
  const double m_dist = 0.004;  // N m, 1.6 rad/s^2 on roll
  double w = 0.0;
  for (int i = 0; i < 2500; ++i) {  // 5 s
    const Eigen::Vector4d wrench =
        WrenchFromRotorSpeeds(params, c.Update(cmd, Eigen::Vector3d(w, 0, 0), kDtS));
    w += (wrench(1) - m_dist) / params.inertia_B_kgm2(0) * kDtS;
  }
  // PI loop s^2 + kp s + ki with poles at -1.8 and -23.2 1/s: after 5 s the error is about
  // e^-9 of the proportional-only offset m_dist / (J kp) = 0.064 rad/s, i.e. 1e-5; bound 1e-3
  EXPECT_NEAR(w, 0.0, 1e-3);
}

}  // namespace
}  // namespace hpa
