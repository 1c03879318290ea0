#include "hpa/controller/hpa_mpc.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <limits>

#include "closed_loop_sim.h"
#include "hpa/controller/geometric_controller.h"

namespace hpa {
namespace {

SystemState HoverAt(const Params& params, const Eigen::Vector3d& p_WQ_W) {
  SystemState s;
  s.FromVector(HybridModel(params).HoverState(p_WQ_W));
  return s;
}

std::shared_ptr<Reference> HoverRef(const Params& params) {
  return MakeHoverReference(params, Eigen::Vector3d(0, 0, 1.0));
}

void ExpectInBounds(const Params& params, const std::vector<InputVector>& u) {
  for (const InputVector& uk : u) {
    EXPECT_GE(uk.minCoeff(), params.motor_speed_min_radps);
    EXPECT_LE(uk.maxCoeff(), params.motor_speed_max_radps);
  }
}

TEST(OcpTest, CameraTransformOfHangingPayload) {
  const Params params;
  const Ocp ocp = BuildOcp(params, *HoverRef(params), 0.0, CableMode::kTaut, 1.0);
  const StateVector x = HybridModel(params).HoverState(Eigen::Vector3d(0, 0, 1.5));
  // payload l below the body, camera 0.05 m below the body looking down: p_C = (0, 0, l - 0.05)
  const Eigen::Vector3d p_C = PayloadInCamera(ocp, x);
  EXPECT_TRUE(p_C.isApprox(Eigen::Vector3d(0, 0, params.cable_length_m - 0.05), 1e-12));
  // payload displaced +x in world (body level): camera x = body x -> positive
  StateVector x2 = x;
  x2(StateIndex::kPayloadPos) += 0.1;
  x2(StateIndex::kPayloadPos + 1) += 0.1;
  const Eigen::Vector3d p_C2 = PayloadInCamera(ocp, x2);
  EXPECT_NEAR(p_C2.x(), 0.1, 1e-12);
  EXPECT_NEAR(p_C2.y(), -0.1, 1e-12);  // camera y = -body y
}

// L_cam is evaluated with the camera at the stage's reference attitude: no attitude lever
// (zero quaternion Jacobian), the slack weight applies in slack mode, and the residual is
// sqrt(pw Q_cam) times the level-camera offset.
TEST(OcpTest, PerceptionCostHasNoAttitudeLever) {
  const Params params;
  const Ocp ocp = BuildOcp(params, *HoverRef(params), 0.0, CableMode::kSlack, 2.0);
  SystemState s;
  s.FromVector(HybridModel(params).HoverState(Eigen::Vector3d(0, 0, 1.5)));
  s.p_WL_W = s.p_WQ_W + Eigen::Vector3d(0.3, 0.1, -0.2);  // held beside, cable slack
  s.q_WB = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 1, 0).normalized());
  ResidualVector r;
  ResidualStateJacobian r_x;
  ResidualInputJacobian r_u;
  StageResidual(ocp, 1, s.ToVector(), ocp.u_ref[1], &r, &r_x, &r_u);
  constexpr int kCamRow = kNx + kNu;
  EXPECT_EQ((r_x.block<2, 4>(kCamRow, StateIndex::kQuat).norm()), 0.0);
  const double scale = std::sqrt(2.0 * ocp.weights.q_cam_slack_per_m2.x());
  // level camera: camera x = body x = world x, camera y = -world y (rounding-level bound)
  EXPECT_NEAR(r(kCamRow), scale * 0.3, 1e-12);
  EXPECT_NEAR(r(kCamRow + 1), -scale * 0.1, 1e-12);
  EXPECT_TRUE(CostPayloadInCamera(ocp, 1, s.ToVector())
                  .head<2>()
                  .isApprox(Eigen::Vector2d(0.3, -0.1), 1e-12));
}

TEST(OcpTest, SlackCameraCostHasADeadZone) {
  const Params params;
  Ocp ocp = BuildOcp(params, *HoverRef(params), 0.0, CableMode::kSlack, 1.0);
  SystemState s;
  s.FromVector(HybridModel(params).HoverState(Eigen::Vector3d(0, 0, 1.5)));
  // payload held 0.3 m below the body origin: depth 0.25 m below the lens
  s.p_WL_W = s.p_WQ_W + Eigen::Vector3d(0.1, 0.05, -0.3);
  SetCameraDeadzone(s, &ocp);
  const double f = params.CameraFocalPx();
  const Eigen::Vector2d dead = ocp.weights.cam_slack_deadzone_fraction * 0.25 *
                               Eigen::Vector2d(640.0 / f, 360.0 / f);
  EXPECT_TRUE(ocp.cam_slack_deadzone_m.isApprox(dead, 1e-12));
  constexpr int kCamRow = kNx + kNu;
  ResidualVector r;
  ResidualStateJacobian r_x;
  ResidualInputJacobian r_u;
  // inside the dead zone: no cost, no gradient
  StageResidual(ocp, 1, s.ToVector(), ocp.u_ref[1], &r, &r_x, &r_u);
  EXPECT_EQ(r.segment<2>(kCamRow).norm(), 0.0);
  EXPECT_EQ(r_x.middleRows<2>(kCamRow).norm(), 0.0);
  // beyond it: the excess, with the sign of the offset (camera y = -world y)
  s.p_WL_W = s.p_WQ_W + Eigen::Vector3d(0.3, -0.2, -0.3);
  StageResidual(ocp, 1, s.ToVector(), ocp.u_ref[1], &r, &r_x, &r_u);
  const double scale = std::sqrt(ocp.weights.q_cam_slack_per_m2.x());
  EXPECT_NEAR(r(kCamRow), scale * (0.3 - dead.x()), 1e-12);
  EXPECT_NEAR(r(kCamRow + 1), scale * (0.2 - dead.y()), 1e-12);
  // a payload thrown above the lens plane cannot be brought into view: L_cam off
  s.p_WL_W = s.p_WQ_W + Eigen::Vector3d(0.3, -0.2, 0.1);
  SetCameraDeadzone(s, &ocp);
  StageResidual(ocp, 1, s.ToVector(), ocp.u_ref[1], &r, &r_x, &r_u);
  EXPECT_EQ(r.segment<2>(kCamRow).norm(), 0.0);
}

TEST(OcpTest, SoftLimitsArePenalisedOnlyBeyondTheirBounds) {
  const Params params;
  const Ocp ocp = BuildOcp(params, *HoverRef(params), 0.0, CableMode::kTaut, 1.0);
  const HybridModel model(params);
  const InputVector u = ocp.u_ref[0];
  ResidualVector r;
  constexpr int kTiltRow = kNx + kNu + 2;
  constexpr int kRateRow = kTiltRow + 1;
  SystemState s;
  s.FromVector(model.HoverState(Eigen::Vector3d(0, 0, 1.5)));
  // 40 deg tilt and 5.9 rad/s: inside the 45 deg / 6 rad/s limits, no penalty
  s.q_WB = Eigen::AngleAxisd(40 * M_PI / 180, Eigen::Vector3d::UnitX());
  s.w_B = Eigen::Vector3d(5.9, -5.9, 0);
  StageResidual(ocp, 1, s.ToVector(), u, &r, nullptr, nullptr);
  EXPECT_EQ(r(kTiltRow), 0.0);
  EXPECT_TRUE(r.segment<3>(kRateRow).isZero(0.0));
  // 50 deg and 7 rad/s: one-sided quadratic penalty with the closed-form residual
  s.q_WB = Eigen::AngleAxisd(50 * M_PI / 180, Eigen::Vector3d::UnitY());
  s.w_B = Eigen::Vector3d(0, -7.0, 0);
  StageResidual(ocp, 1, s.ToVector(), u, &r, nullptr, nullptr);
  const OcpWeights& w = ocp.weights;
  const double h_tilt = std::cos(w.tilt_max_rad) - std::cos(50 * M_PI / 180);
  EXPECT_NEAR(r(kTiltRow), std::sqrt(w.tilt_weight) * h_tilt, 1e-12);
  EXPECT_NEAR(r(kRateRow + 1), std::sqrt(w.body_rate_weight) * 1.0, 1e-12);
}

TEST(OcpTest, CostGradientMatchesFiniteDifferences) {
  const Params params;
  LissajousSpec spec;
  const auto ref = MakeLissajousReference(params, spec);
  const HybridModel model(params);
  for (CableMode mode : {CableMode::kTaut, CableMode::kSlack}) {
    const Ocp ocp = BuildOcp(params, *ref, 2.5, mode, 1.0);
    StateVector x0 = model.HoverState(Eigen::Vector3d(0.1, 0.2, 1.4));
    x0(StateIndex::kBodyRate) = 7.0;  // beyond the soft rate limit: its penalty is active
    std::vector<InputVector> u(ocp.horizon_steps);
    for (int k = 0; k < ocp.horizon_steps; ++k) {
      u[k] = params.HoverMotorSpeedRadps() * InputVector(1.0 + 0.01 * k, 0.98, 1.02, 1.0);
    }
    Eigen::VectorXd grad;
    OcpCostAndGradient(ocp, model, x0, u, &grad);
    for (int i = 0; i < kNu * ocp.horizon_steps; i += 3) {
      const double h = 1e-2;  // rad/s on ~1e3 rad/s inputs
      std::vector<InputVector> up = u, um = u;
      up[i / kNu](i % kNu) += h;
      um[i / kNu](i % kNu) -= h;
      const double fd = (OcpCost(ocp, model, x0, up) - OcpCost(ocp, model, x0, um)) / (2 * h);
      // central-difference truncation h^2 f''' ~ 1e-4 * 1e-6 relative; kinks of the soft
      // penalties are avoided by construction; 1e-5 relative + 1e-7 absolute
      EXPECT_NEAR(grad(i), fd, 1e-5 * std::abs(fd) + 1e-7) << "mode " << ToString(mode);
    }
  }
}

TEST(HpaMpcTest, HoverAtReferenceKeepsHoverThrust) {
  const Params params;
  HpaMpc mpc(params, HoverRef(params), MpcSettings());
  SystemState s = HoverAt(params, Eigen::Vector3d(0, 0, 1.5));
  const ControlOutput out = mpc.Update(s);
  EXPECT_EQ(out.status, ControlStatus::kSuccess);
  // at the reference the optimum is hover: thrust within 1% and rates below 0.01 rad/s
  // (the only pull away from hover is the 1e-12-scale rounding of the references)
  EXPECT_NEAR(out.command.thrust_N, params.HoverThrustN(), 0.01 * params.HoverThrustN());
  EXPECT_LT(out.command.w_B_radps.norm(), 1e-2);
  EXPECT_LT(out.cost, 1e-3);
  ExpectInBounds(params, mpc.plan_inputs());
}

TEST(HpaMpcTest, BoundsRespectedFromLargeOffset) {
  const Params params;
  HpaMpc mpc(params, HoverRef(params), MpcSettings());
  SystemState s = HoverAt(params, Eigen::Vector3d(1.5, -1.0, 0.5));  // 1.8 m away, 1 m low
  bool some_bound_active = false;
  for (int i = 0; i < 5; ++i) {
    s.time_s = i / 150.0;
    const ControlOutput out = mpc.Update(s);
    ASSERT_TRUE(out.status == ControlStatus::kSuccess ||
                out.status == ControlStatus::kMaxIterations);
    ExpectInBounds(params, mpc.plan_inputs());
    for (const InputVector& u : mpc.plan_inputs()) {
      some_bound_active |= (u.maxCoeff() >= params.motor_speed_max_radps - 1e-9) ||
                           (u.minCoeff() <= params.motor_speed_min_radps + 1e-9);
    }
  }
  EXPECT_TRUE(some_bound_active) << "the offset should saturate some rotor";
}

TEST(HpaMpcTest, WarmStartReducesCost) {
  // fly 0.1 s from an offset on the analytic plant; then RTI from the shifted previous plan
  // must beat RTI from hover at the new state
  const Params params;
  HpaMpc mpc(params, HoverRef(params), MpcSettings());
  testing_util::HybridPlant plant(
      params, HybridModel(params).HoverState(Eigen::Vector3d(0.4, 0.0, 1.3)), CableMode::kTaut);
  testing_util::RunClosedLoop(params, &mpc, &plant, 0.1);
  const SystemState s = plant.State(0.1);
  const Ocp ocp = mpc.BuildProblem(s);
  const StateVector x0 = s.ToVector();
  const RtiResult warm = RtiIteration(ocp, mpc.model(), x0, mpc.WarmStart(s.time_s));
  const RtiResult cold = RtiIteration(
      ocp, mpc.model(), x0,
      std::vector<InputVector>(10, InputVector::Constant(params.HoverMotorSpeedRadps())));
  std::printf("warm start: guess %.3f -> %.3f, cold: guess %.3f -> %.3f\n", warm.cost_guess,
              warm.cost, cold.cost_guess, cold.cost);
  EXPECT_LT(warm.cost_guess, cold.cost_guess);
  EXPECT_LT(warm.cost, cold.cost);
  EXPECT_LT(warm.cost, warm.cost_guess);
}

TEST(HpaMpcTest, RepeatedRtiConvergesToNloptOptimum) {
  const Params params;
  const HybridModel model(params);
  const auto ref = HoverRef(params);
  const Ocp ocp = BuildOcp(params, *ref, 0.0, CableMode::kTaut, 1.0);
  const StateVector x0 = model.HoverState(Eigen::Vector3d(0.3, -0.2, 1.4));
  std::vector<InputVector> u(10, InputVector::Constant(params.HoverMotorSpeedRadps()));
  const RtiResult first = RtiIteration(ocp, model, x0, u);
  RtiResult r = first;
  for (int i = 0; i < 15; ++i) r = RtiIteration(ocp, model, x0, r.u);
  const NloptResult nl = NloptSolve(ocp, model, x0, u);
  ASSERT_TRUE(nl.status == ControlStatus::kSuccess) << nl.nlopt_code;
  // NLopt reaches the (local) optimum; one RTI is close to it, iterated Gauss-Newton agrees to
  // 1% (GN converges linearly at the residual-curvature rate; measured ratio ~1.000x)
  EXPECT_LE(nl.cost, first.cost * (1 + 1e-9));
  EXPECT_NEAR(r.cost, nl.cost, 0.01 * nl.cost);
  ExpectInBounds(params, nl.u);
}

TEST(HpaMpcTest, NonFiniteStateGivesSafeHover) {
  const Params params;
  for (const std::string type : {"hpa_mpc", "nonhybrid_mpc", "geometric"}) {
    ControllerConfig config;
    config.type = type;
    auto c = MakeController(config, params, HoverRef(params));
    SystemState s = HoverAt(params, Eigen::Vector3d(0, 0, 1.5));
    c->Update(s);
    s.p_WL_W.x() = std::numeric_limits<double>::quiet_NaN();
    s.time_s = 0.01;
    const ControlOutput out = c->Update(s);
    EXPECT_EQ(out.status, ControlStatus::kNonFinite) << type;
    EXPECT_TRUE(out.command.w_B_radps.isZero(0.0)) << type;
    EXPECT_DOUBLE_EQ(out.command.thrust_N, params.HoverThrustN()) << type;
  }
}

TEST(HpaMpcTest, UnsolvableStateFallsBackToHover) {
  // finite state whose prediction overflows: the solve fails, the shifted previous plan is not
  // usable either (same overflow), so the controller must fall back to a level hover command
  const Params params;
  HpaMpc mpc(params, HoverRef(params), MpcSettings());
  SystemState s = HoverAt(params, Eigen::Vector3d(0, 0, 1.5));
  ASSERT_EQ(mpc.Update(s).status, ControlStatus::kSuccess);
  s.time_s = 1.0 / 150.0;
  s.w_B = Eigen::Vector3d(1e155, 0, 0);  // its square overflows to inf in the dynamics
  ASSERT_TRUE(s.AllFinite());
  const ControlOutput out = mpc.Update(s);
  EXPECT_EQ(out.status, ControlStatus::kFallback);
  EXPECT_TRUE(out.command.w_B_radps.isZero(0.0));
  EXPECT_DOUBLE_EQ(out.command.thrust_N, params.HoverThrustN());
  EXPECT_TRUE(mpc.plan_inputs().empty());  // next call starts again from hover
}

TEST(HpaMpcTest, FactoryAndModes) {
  const Params params;
  ControllerConfig config;
  config.type = "nonhybrid_mpc";
  auto c = MakeController(config, params, HoverRef(params));
  auto* mpc = dynamic_cast<HpaMpc*>(c.get());
  ASSERT_NE(mpc, nullptr);
  SystemState s = HoverAt(params, Eigen::Vector3d(0, 0, 1.5));
  s.mode = CableMode::kSlack;
  // nonhybrid ignores the estimated mode and has no perception cost
  EXPECT_EQ(mpc->BuildProblem(s).mode, CableMode::kTaut);
  EXPECT_EQ(mpc->BuildProblem(s).perception_weight, 0.0);
  config.type = "hpa_mpc";
  config.perception_weight = 0.5;
  auto h = MakeController(config, params, HoverRef(params));
  EXPECT_EQ(dynamic_cast<HpaMpc*>(h.get())->BuildProblem(s).mode, CableMode::kSlack);
  EXPECT_EQ(dynamic_cast<HpaMpc*>(h.get())->BuildProblem(s).perception_weight, 0.5);
  EXPECT_DOUBLE_EQ(h->RateHz(), 150.0);
  config.type = "geometric";
  EXPECT_NE(
      dynamic_cast<GeometricController*>(MakeController(config, params, HoverRef(params)).get()),
      nullptr);
  config.type = "pid";
  EXPECT_THROW(MakeController(config, params, HoverRef(params)), std::invalid_argument);
  config.type = "hpa_mpc";
  config.solver = "ipopt";
  EXPECT_THROW(MakeController(config, params, HoverRef(params)), std::invalid_argument);
  EXPECT_STREQ(ToString(ControlStatus::kQpFailure), "qp_failure");
  EXPECT_STREQ(ToString(ControlStatus::kNonFinite), "non_finite");
}

}  // namespace
}  // namespace hpa
