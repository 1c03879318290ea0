// The analytic hybrid model (hpa::HybridModel) against MuJoCo (Drake habit: a hand-written
// dynamics model is tested against the multibody engine from the same state and input).
// Motors are held at constant speed in both (World::SetState sets the motor state, no lag).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>

#include "hpa/models/hybrid_model.h"
#include "hpa/models/params.h"
#include "hpa/sim/world.h"

namespace hpa::sim {
namespace {

// Largest differences over a rollout.
struct Residual {
  double payload_pos_m = 0, quad_pos_m = 0, payload_vel_mps = 0, quad_vel_mps = 0;
  double attitude_rad = 0, body_rate_radps = 0;
  bool mujoco_mode_constant = true;  // MuJoCo's true mode never left the rollout's mode
};

Residual Rollout(const char* name, const StateVector& x0, const InputVector& u, CableMode mode,
                 double duration_s) {
  WorldConfig config;
  config.params = LoadParams(DefaultParamsPath());
  World world(config);
  const HybridModel model(config.params);
  world.SetState(x0, u);
  StateVector x = x0;
  Residual r;
  using I = StateIndex;
  const int steps = static_cast<int>(std::lround(duration_s / World::kPhysicsDt_s));
  for (int k = 0; k < steps; ++k) {
    world.Step();
    // RK4 at the physics step (local error O(dt^5)) is far finer than MuJoCo's semi-implicit
    // Euler, so the residual is the physics difference (Euler, the soft cable)
    x = model.Step(x, u, mode, World::kPhysicsDt_s);
    const Truth t = world.GetTruth();
    const StateVector xm = t.state.ToVector();
    r.mujoco_mode_constant &= t.state.mode == mode;
    auto err = [&](int i) { return (xm.segment<3>(i) - x.segment<3>(i)).norm(); };
    r.payload_pos_m = std::max(r.payload_pos_m, err(I::kPayloadPos));
    r.quad_pos_m = std::max(r.quad_pos_m, err(I::kQuadPos));
    r.payload_vel_mps = std::max(r.payload_vel_mps, err(I::kPayloadVel));
    r.quad_vel_mps = std::max(r.quad_vel_mps, err(I::kQuadVel));
    r.body_rate_radps = std::max(r.body_rate_radps, err(I::kBodyRate));
    const Eigen::Quaterniond q_model(x(I::kQuat), x(I::kQuat + 1), x(I::kQuat + 2),
                                     x(I::kQuat + 3));
    r.attitude_rad = std::max(r.attitude_rad, q_model.angularDistance(t.state.q_WB));
  }
  std::printf(
      "[measured] %-22s %.2f s: payload pos %.2e m, quad pos %.2e m, payload vel %.2e m/s, quad "
      "vel %.2e m/s, attitude %.2e rad, body rate %.2e rad/s\n",
      name, duration_s, r.payload_pos_m, r.quad_pos_m, r.payload_vel_mps, r.quad_vel_mps,
      r.attitude_rad, r.body_rate_radps);
  return r;
}

// Largest residuals measured over the four cases below (sim_test, "[measured]" lines):
//   payload position 1.47e-3 m   (slack: Euler's 0.5 g dt t position lag of a ballistic payload)
//   quad position    2.15e-4 m   (taut accelerating)
//   payload velocity 1.06e-2 m/s (one step g dt = 9.8e-3: the limit engages one step after the
//                                 cable reaches exactly l, then holds)
//   quad velocity    1.48e-3 m/s (taut accelerating)
//   attitude         1.11e-3 rad (taut accelerating)
//   body rate        7.03e-4 rad/s (taut accelerating)
// Each tolerance is 10x its measured maximum; a wrong frame, sign, mass, arm or gear shows up
// as centimetres, 0.1 m/s and 0.01 rad within these rollouts.
constexpr double kPayloadPosTol_m = 0.015;
constexpr double kQuadPosTol_m = 0.002;
constexpr double kPayloadVelTol_mps = 0.1;
constexpr double kQuadVelTol_mps = 0.015;
constexpr double kAttitudeTol_rad = 0.011;
constexpr double kBodyRateTol_radps = 0.007;

void ExpectAgree(const Residual& r) {
  EXPECT_TRUE(r.mujoco_mode_constant) << "MuJoCo's cable left the rollout's mode";
  EXPECT_LT(r.payload_pos_m, kPayloadPosTol_m);
  EXPECT_LT(r.quad_pos_m, kQuadPosTol_m);
  EXPECT_LT(r.payload_vel_mps, kPayloadVelTol_mps);
  EXPECT_LT(r.quad_vel_mps, kQuadVelTol_mps);
  EXPECT_LT(r.attitude_rad, kAttitudeTol_rad);
  EXPECT_LT(r.body_rate_radps, kBodyRateTol_radps);
}

class ModelVsPhysicsTest : public ::testing::Test {
 protected:
  Params p_ = LoadParams(DefaultParamsPath());
  HybridModel model_{p_};
  double w_hover_ = p_.HoverMotorSpeedRadps();                    // quad + payload
  double w_quad_ = std::sqrt(p_.quad_mass_kg * p_.gravity_mps2 /  // quad alone
                             (4 * p_.k_f_N_per_radps2));
};

TEST_F(ModelVsPhysicsTest, TautHangingAtHover) {
  const StateVector x0 = model_.HoverState(Eigen::Vector3d(0, 0, 2));
  const Residual r =
      Rollout("taut hover", x0, InputVector::Constant(w_hover_), CableMode::kTaut, 0.5);
  ExpectAgree(r);
}

TEST_F(ModelVsPhysicsTest, TautSwinging) {
  // payload 25 deg off vertical, released at rest; quad level at hover thrust
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0, 0, 2);
  const double a = 25.0 * M_PI / 180.0;
  s.p_WL_W = s.p_WQ_W + p_.cable_length_m * Eigen::Vector3d(std::sin(a), 0, -std::cos(a));
  const Residual r = Rollout("taut swinging", s.ToVector(), InputVector::Constant(w_hover_),
                             CableMode::kTaut, 0.5);
  ExpectAgree(r);
}

TEST_F(ModelVsPhysicsTest, TautAcceleratingWithUnequalRotors) {
  // climbing, rolling, pitching and yawing at once, from a moving, rotating start
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0, 0, 2);
  s.p_WL_W = s.p_WQ_W + Eigen::Vector3d(0, 0, -p_.cable_length_m);
  s.v_WQ_W = s.v_WL_W = Eigen::Vector3d(0.5, -0.3, 0.2);
  s.w_B = Eigen::Vector3d(0.2, -0.1, 0.3);
  const InputVector u = w_hover_ * Eigen::Vector4d(1.08, 1.02, 1.06, 1.0);
  const Residual r = Rollout("taut accelerating", s.ToVector(), u, CableMode::kTaut, 0.3);
  ExpectAgree(r);
}

TEST_F(ModelVsPhysicsTest, SlackPayloadThrownUpward) {
  // payload 0.3 m below, thrown up at 1.5 m/s: in the air (cable slack) for the whole 0.3 s
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0, 0, 2);
  s.p_WL_W = Eigen::Vector3d(0.05, 0, 1.7);
  s.v_WL_W = Eigen::Vector3d(0.2, 0.1, 1.5);
  s.w_B = Eigen::Vector3d(0.1, 0.2, -0.1);
  const InputVector u = w_quad_ * Eigen::Vector4d(1.03, 0.98, 1.01, 0.99);
  const Residual r = Rollout("slack thrown upward", s.ToVector(), u, CableMode::kSlack, 0.3);
  ExpectAgree(r);
}

}  // namespace
}  // namespace hpa::sim
