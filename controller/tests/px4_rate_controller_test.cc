// The PX4-like rate loop: normalisation, signs, saturation and desaturation priority against
// closed-form values, the integrator's anti-windup and limit, non-finite input, and a roll-rate
// step on the analytic plant.
#include "hpa/autopilot/px4_rate_controller.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "closed_loop_sim.h"
#include "hpa/models/rotor_model.h"

namespace hpa {
namespace {

constexpr double kDtS = 0.001;  // 1 kHz

double ThrustRangeN(const Params& p) {
  return p.k_f_N_per_radps2 * (p.motor_speed_max_radps * p.motor_speed_max_radps -
                               p.motor_speed_min_radps * p.motor_speed_min_radps);
}

TEST(Px4RateControllerTest, TorqueScaleIsPx4sNormalisationInClosedForm) {
  const Params p;
  const Px4TorqueScale s = Px4RateController::TorqueScale(p);
  const double df = ThrustRangeN(p);
  // 1e-12 relative: a 4x4 inverse
  EXPECT_NEAR(s.torque_Nm(0), 2 * p.arm_length_m * df, 1e-12 * s.torque_Nm(0));
  EXPECT_NEAR(s.torque_Nm(1), 2 * p.arm_length_m * df, 1e-12 * s.torque_Nm(1));
  EXPECT_NEAR(s.torque_Nm(2), 4 * p.k_m_Nm_per_radps2 / p.k_f_N_per_radps2 * df,
              1e-12 * s.torque_Nm(2));
  EXPECT_NEAR(s.thrust_N, 4 * df, 1e-12 * s.thrust_N);
  // the numbers of the file comment (params.yaml)
  EXPECT_NEAR(s.torque_Nm(0), 1.502, 1e-3);
  EXPECT_NEAR(s.torque_Nm(2), 0.3205, 1e-4);
}

TEST(Px4RateControllerTest, HoverCommandGivesHoverSpeeds) {
  const Params p;
  Px4RateController c(p, Px4RateParams());
  BodyRateCommand cmd;
  cmd.thrust_N = p.HoverThrustN();
  const InputVector w = c.Update(cmd, Eigen::Vector3d::Zero());
  // 1e-9 relative: a 4x4 inverse and a square root
  EXPECT_TRUE(w.isApprox(InputVector::Constant(p.HoverMotorSpeedRadps()), 1e-9));
  EXPECT_TRUE(c.status().input_valid);
}

// The status says what thrust the allocation made: the hover command unsaturated and made as
// asked; a command of twice the rotors' total lowered to what they give, flagged saturated; the
// figure equals the collective thrust of the rotor speeds sent.
TEST(Px4RateControllerTest, StatusGivesTheAllocatedThrustAndSaturation) {
  const Params p;
  Px4RateController c(p, Px4RateParams());
  BodyRateCommand cmd;
  cmd.thrust_N = p.HoverThrustN();
  InputVector w = c.Update(cmd, Eigen::Vector3d::Zero());
  EXPECT_FALSE(c.status().saturated);
  EXPECT_NEAR(c.status().thrust_allocated_N, p.HoverThrustN(), 1e-9);
  EXPECT_NEAR(c.status().thrust_allocated_N, p.k_f_N_per_radps2 * w.squaredNorm(), 1e-9);
  cmd.thrust_N = 2.0 * 4.0 * p.k_f_N_per_radps2 * std::pow(p.motor_speed_max_radps, 2);
  w = c.Update(cmd, Eigen::Vector3d::Zero());
  EXPECT_TRUE(c.status().saturated);
  EXPECT_NEAR(c.status().thrust_allocated_N, p.k_f_N_per_radps2 * w.squaredNorm(), 1e-9);
  EXPECT_LT(c.status().thrust_allocated_N, 0.51 * cmd.thrust_N);
}

TEST(Px4RateControllerTest, ProportionalTorqueSignsPerAxis) {
  const Params p;
  const Px4RateParams px4;
  for (int axis = 0; axis < 3; ++axis) {
    Px4RateController c(p, px4);
    BodyRateCommand cmd;
    cmd.thrust_N = p.HoverThrustN();
    cmd.w_B_radps(axis) = 1.0;
    const Eigen::Vector4d wrench = WrenchFromRotorSpeeds(p, c.Update(cmd, {0, 0, 0}));
    // first step: no integral yet, no derivative; yaw goes through the 2 Hz first-order filter
    double expected = px4.k(axis) * px4.p(axis);
    if (axis == 2) {
      const double alpha = kDtS / (kDtS + 1.0 / (2 * M_PI * px4.yaw_torque_cutoff_hz));
      expected *= alpha;
    }
    // 1e-9 N m: rounding through the rotor speeds
    EXPECT_NEAR(wrench(1 + axis), expected * c.scale().torque_Nm(axis), 1e-9);
    EXPECT_GT(wrench(1 + axis), 0.0);
    for (int other = 0; other < 3; ++other) {
      if (other != axis) {
        EXPECT_NEAR(wrench(1 + other), 0.0, 1e-9);
      }
    }
    EXPECT_NEAR(wrench(0), p.HoverThrustN(), 1e-9);
  }
}

TEST(Px4RateControllerTest, DerivativeActsOnTheFilteredGyroDerivative) {
  const Params p;
  const Px4RateParams px4;
  Px4RateController c(p, px4);
  BodyRateCommand cmd;
  cmd.thrust_N = p.HoverThrustN();
  c.Update(cmd, Eigen::Vector3d::Zero());
  // the vehicle starts rolling at 0.5 rad/s; the command stays zero
  const Eigen::Vector3d gyro(0.5, 0, 0);
  c.Update(cmd, gyro);
  ButterworthLowPass rate_f(px4.rate_hz, px4.gyro_cutoff_hz),
      accel_f(px4.rate_hz, px4.dgyro_cutoff_hz);
  rate_f.Apply(Eigen::Vector3d::Zero());
  accel_f.Apply(Eigen::Vector3d::Zero());
  const double rate = rate_f.Apply(gyro)(0);
  const double accel = accel_f.Apply(gyro / kDtS)(0);
  // P on the filtered rate and D on the filtered derivative, both against the motion
  const double expected = -px4.p(0) * rate - px4.d(0) * accel;
  EXPECT_NEAR(c.status().torque_sp(0), expected, 1e-12);
  EXPECT_LT(c.status().torque_sp(0), 0.0);
}

TEST(Px4RateControllerTest, RollSaturationLowersThrustAndKeepsRoll) {
  const Params p;
  // thrust 0.8, roll 0.5: rotors 0.8 +- 0.5 / sqrt(2); the high pair exceeds 1 by
  // 0.8 + 0.3536 - 1 = 0.1536, so the thrust drops by exactly that and roll is kept
  const Px4Allocation a = Px4RateController::AllocateAirmodeDisabled(
      p, Eigen::Vector3d(0.5, 0, 0), 0.8, Px4RateParams{}.yaw_headroom);
  const double over = 0.8 + 0.5 / std::sqrt(2.0) - 1.0;
  EXPECT_NEAR(a.torque(0), 0.5, 1e-12);
  EXPECT_NEAR(a.thrust, 0.8 - over, 1e-12);
  EXPECT_NEAR(a.u.maxCoeff(), 1.0, 1e-12);
  EXPECT_NEAR(a.torque(1), 0.0, 1e-12);
  EXPECT_NEAR(a.torque(2), 0.0, 1e-12);
}

TEST(Px4RateControllerTest, RollBeyondTheRotorsIsScaledAtMidThrust) {
  const Params p;
  // thrust 0.5, roll 1: rotors 0.5 +- 0.707 break both bounds equally; thrust cannot help (its
  // gains cancel), roll is scaled to the most the rotors give at this thrust, 0.5 * sqrt(2)
  const Px4Allocation a = Px4RateController::AllocateAirmodeDisabled(
      p, Eigen::Vector3d(1.0, 0, 0), 0.5, Px4RateParams{}.yaw_headroom);
  EXPECT_NEAR(a.torque(0), 0.5 * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(a.thrust, 0.5, 1e-12);
  EXPECT_NEAR(a.u.maxCoeff(), 1.0, 1e-12);
  EXPECT_NEAR(a.u.minCoeff(), 0.0, 1e-12);
}

TEST(Px4RateControllerTest, YawHasTheLowestPriority) {
  const Params p;
  // thrust 0.5, roll 0.3 (rotors +-0.2121), yaw 0.5 (rotors +-0.5): the rotor with both negative
  // would reach -0.2121; yaw alone gives way, to 0.5 - 0.2121, roll and thrust are kept
  const Px4Allocation a = Px4RateController::AllocateAirmodeDisabled(
      p, Eigen::Vector3d(0.3, 0, 0.5), 0.5, Px4RateParams{}.yaw_headroom);
  EXPECT_NEAR(a.torque(0), 0.3, 1e-12);
  EXPECT_NEAR(a.thrust, 0.5, 1e-12);
  EXPECT_NEAR(a.torque(2), 0.5 - 0.3 / std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(a.u.minCoeff(), 0.0, 1e-12);

  // near full thrust: roll first lowers the thrust (0.9 + 0.1414 - 1 = 0.0414), yaw 0.1 then
  // fits inside the 15 % headroom and the thrust is lowered again by what yaw added (0.1):
  // roll and yaw are both kept, the thrust gives way
  const Px4Allocation b = Px4RateController::AllocateAirmodeDisabled(
      p, Eigen::Vector3d(0.2, 0, 0.1), 0.9, Px4RateParams{}.yaw_headroom);
  EXPECT_NEAR(b.torque(0), 0.2, 1e-12);
  EXPECT_NEAR(b.torque(2), 0.1, 1e-12);
  EXPECT_NEAR(b.thrust, 0.9 - (0.9 + 0.2 / std::sqrt(2.0) - 1.0) - 0.1, 1e-12);
  EXPECT_LE(b.u.maxCoeff(), 1.0);
}

TEST(Px4RateControllerTest, IntegratorStopsGrowingInTheSaturatedDirection) {
  const Params p;
  const Px4RateParams px4;
  Px4RateController c(p, px4);
  BodyRateCommand cmd;
  cmd.thrust_N = p.HoverThrustN();
  // 6 rad/s of roll error: P alone asks 0.9, more than the 0.707 the rotors give at hover-ish
  // thrust, so the allocation saturates positive; the integrator moves only on the first step
  // (no flag yet), scaled by PX4's i_factor 1 - (e / 400 deg/s)^2
  cmd.w_B_radps = Eigen::Vector3d(6.0, 0, 0);
  c.Update(cmd, Eigen::Vector3d::Zero());
  const double e_ratio = 6.0 / (400.0 * M_PI / 180.0);
  const double first = (1 - e_ratio * e_ratio) * px4.i(0) * 6.0 * kDtS;
  EXPECT_NEAR(c.status().integral(0), first, 1e-15);
  EXPECT_TRUE(c.status().saturated_positive(0));
  EXPECT_FALSE(c.status().saturated_negative(0));
  for (int k = 0; k < 500; ++k) c.Update(cmd, Eigen::Vector3d::Zero());
  EXPECT_NEAR(c.status().integral(0), first, 1e-15);
  // an error of the other sign still unwinds it
  cmd.w_B_radps = Eigen::Vector3d(-0.1, 0, 0);
  c.Update(cmd, Eigen::Vector3d::Zero());
  EXPECT_LT(c.status().integral(0), first);

  // the mirror image: negative saturation stops negative growth
  Px4RateController n(p, px4);
  cmd.w_B_radps = Eigen::Vector3d(-6.0, 0, 0);
  for (int k = 0; k < 500; ++k) n.Update(cmd, Eigen::Vector3d::Zero());
  EXPECT_TRUE(n.status().saturated_negative(0));
  EXPECT_NEAR(n.status().integral(0), -first, 1e-15);
}

TEST(Px4RateControllerTest, IntegratorIsClampedToItsLimit) {
  const Params p;
  const Px4RateParams px4;
  Px4RateController c(p, px4);
  BodyRateCommand cmd;
  cmd.thrust_N = p.HoverThrustN();
  // unsaturated at hover thrust (0.40): 0.15 + 0.3 gives rotors 0.40 +- 0.32
  cmd.w_B_radps = Eigen::Vector3d(1.0, 0, 0);
  // 0.2 * 0.98 per s reaches 0.3 in 1.53 s; run 3 s
  for (int k = 0; k < 3000; ++k) c.Update(cmd, Eigen::Vector3d::Zero());
  EXPECT_DOUBLE_EQ(c.status().integral(0), px4.integrator_limit(0));
  EXPECT_FALSE(c.status().saturated_positive(0));
  Px4RateController n(p, px4);
  cmd.w_B_radps = Eigen::Vector3d(0, -1.0, 0);
  for (int k = 0; k < 3000; ++k) n.Update(cmd, Eigen::Vector3d::Zero());
  EXPECT_DOUBLE_EQ(n.status().integral(1), -px4.integrator_limit(1));
  EXPECT_FALSE(n.status().saturated_negative(1));
}

TEST(Px4RateControllerTest, NonFiniteInputGivesHoverAndResets) {
  const Params p;
  Px4RateController c(p, Px4RateParams());
  BodyRateCommand cmd;
  cmd.thrust_N = p.HoverThrustN();
  cmd.w_B_radps = Eigen::Vector3d(1.0, 0, 0);
  for (int k = 0; k < 100; ++k) c.Update(cmd, Eigen::Vector3d::Zero());
  EXPECT_GT(c.status().integral(0), 0.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const auto& [bad_cmd, bad_gyro] :
       {std::pair{BodyRateCommand{Eigen::Vector3d(nan, 0, 0), 5.0}, Eigen::Vector3d::Zero().eval()},
        std::pair{BodyRateCommand{Eigen::Vector3d::Zero(), inf}, Eigen::Vector3d::Zero().eval()},
        std::pair{cmd, Eigen::Vector3d(0, nan, 0)}}) {
    const InputVector w = c.Update(bad_cmd, bad_gyro);
    EXPECT_FALSE(c.status().input_valid);
    EXPECT_TRUE(w.allFinite());
    EXPECT_TRUE(w.isApprox(InputVector::Constant(p.HoverMotorSpeedRadps()), 1e-9));
    EXPECT_EQ(c.status().integral, Eigen::Vector3d::Zero());
  }
  // and the loop runs again on the next valid sample
  c.Update(cmd, Eigen::Vector3d::Zero());
  EXPECT_TRUE(c.status().input_valid);
}

// A roll-rate step of 1 rad/s from hover on the analytic plant (taut payload) with the motors'
// first-order lag, gyro = true rate, the loop at 1 kHz.
TEST(Px4RateControllerTest, RollRateStepOnTheAnalyticPlant) {
  const Params p;
  SystemState s0;
  s0.p_WQ_W = Eigen::Vector3d(0, 0, 1.5);
  s0.p_WL_W = Eigen::Vector3d(0, 0, 1.5 - p.cable_length_m);
  testing_util::HybridPlant plant(p, s0.ToVector(), CableMode::kTaut);
  Px4RateController c(p, Px4RateParams());
  BodyRateCommand cmd;
  cmd.thrust_N = p.HoverThrustN();
  cmd.w_B_radps = Eigen::Vector3d(1.0, 0, 0);
  InputVector motor = InputVector::Constant(p.HoverMotorSpeedRadps());
  const double lag = 1.0 - std::exp(-kDtS / p.motor_time_constant_s);
  double peak = 0.0, t_90 = -1.0, at_250ms = 0.0, cross_max = 0.0;
  for (int k = 0; k < 250; ++k) {
    const Eigen::Vector3d w_B = plant.State(k * kDtS).w_B;
    const InputVector w_cmd = c.Update(cmd, w_B);
    motor += lag * (w_cmd - motor);
    plant.Step(motor, kDtS);
    const Eigen::Vector3d w_next = plant.State((k + 1) * kDtS).w_B;
    peak = std::max(peak, w_next(0));
    cross_max = std::max(cross_max, w_next.tail<2>().cwiseAbs().maxCoeff());
    if (t_90 < 0 && w_next(0) >= 0.9) t_90 = (k + 1) * kDtS;
    at_250ms = w_next(0);
  }
  // measured (PX4's defaults on this vehicle): 90 % at 0.039 s, peak 1.039 rad/s (3.9 %
  // overshoot), 1.032 rad/s at 0.25 s (the integrator, filled during the rise, still unwinding),
  // cross axes 0. Bounds: 20 % on the rise time, 1.5x the overshoot, the error at 0.25 s within
  // 0.05 (measured 0.032); the cross axes to rounding
  EXPECT_GT(t_90, 0.0);
  EXPECT_LT(t_90, 0.039 * 1.2);
  EXPECT_LT(peak, 1.0 + 0.039 * 1.5);
  EXPECT_NEAR(at_250ms, 1.0, 0.05);
  EXPECT_LT(cross_max, 1e-9);
}

// PX4's per-axis limits (mc_rate_control_params.c): MC_ROLLRATE_P stops at 0.5 where
// MC_PITCHRATE_P goes to 0.6, and MC_ROLLRATE_D stops at 0.01; the defaults sit within them.
TEST(Px4RateParamTableTest, ChecksEachAxisAgainstItsOwnPx4Range) {
  EXPECT_NO_THROW(CheckParamTable(Px4RateParamTable(), "rate_loop.", Px4RateParams{}));
  Px4RateParams roll_p;
  roll_p.p.x() = 0.55;
  EXPECT_THROW(CheckParamTable(Px4RateParamTable(), "rate_loop.", roll_p), std::invalid_argument);
  Px4RateParams pitch_p;
  pitch_p.p.y() = 0.55;
  EXPECT_NO_THROW(CheckParamTable(Px4RateParamTable(), "rate_loop.", pitch_p));
  Px4RateParams roll_d;
  roll_d.d.x() = 0.02;
  EXPECT_THROW(CheckParamTable(Px4RateParamTable(), "rate_loop.", roll_d), std::invalid_argument);
  Px4RateParams yaw_headroom;
  yaw_headroom.yaw_headroom = 1.5;
  EXPECT_THROW(CheckParamTable(Px4RateParamTable(), "rate_loop.", yaw_headroom),
               std::invalid_argument);
}

}  // namespace
}  // namespace hpa
