// The OCP along a rollout: the linearisation RTI and the adjoint share, the adjoint gradient
// against finite differences, the predicted re-taut stage and the step through the jump map
// (ocp_test.cc: the residual terms).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include "hpa/controller/ocp.h"

namespace hpa {
namespace {

// Hover 1 m above the origin.
std::shared_ptr<Reference> HoverRef(const Params& params) {
  return MakeHoverReference(params, Eigen::Vector3d(0, 0, 1.0));
}

// The linearisation RTI and the adjoint share is the simulation OcpCost runs, bit for bit, with
// the dynamics' own Jacobians and no input rows at the terminal stage.
TEST(OcpTest, LinearizationIsTheSimulatedTrajectory) {
  const Params params;
  const Ocp ocp = BuildOcp(params, *MakeLissajousReference(params, LissajousSpec()), 2.5,
                           CableMode::kTaut, 1.0);
  const StateVector x0 = ocp.model->HoverState(Eigen::Vector3d(0.1, 0.2, 1.4));
  std::vector<InputVector> u(ocp.horizon_steps);
  for (int k = 0; k < ocp.horizon_steps; ++k) u[k] = (1.0 + 0.01 * k) * ocp.u_ref[k];
  std::vector<StateVector> x;
  const double cost = OcpCost(ocp, x0, u, &x);
  const OcpLinearization lin = LinearizeAlong(ocp, x0, u);
  EXPECT_EQ(lin.cost, cost);
  ASSERT_EQ(lin.x.size(), x.size());
  for (size_t k = 0; k < x.size(); ++k) EXPECT_EQ(lin.x[k], x[k]) << k;
  for (int k = 0; k < ocp.horizon_steps; ++k) {
    StateVector x_next;
    StateMatrix a;
    InputMatrix b;
    ocp.StepJacobians(k, x[k], u[k], &x_next, &a, &b);
    EXPECT_EQ(lin.a[k], a) << k;
    EXPECT_EQ(lin.b[k], b) << k;
  }
  EXPECT_TRUE(lin.r_u.back().isZero(0.0));
}

// The adjoint gradient of the cost against central differences on every third input (h = 1e-2
// rad/s on ~1e3 rad/s inputs): truncation h^2 f''' ~ 1e-4 * 1e-6 relative, and the callers' states
// avoid the soft penalties' kinks; 1e-5 relative + 1e-7 absolute.
void ExpectGradientMatchesCentralDifferences(const Ocp& ocp, const StateVector& x0,
                                             const std::vector<InputVector>& u) {
  Eigen::VectorXd grad;
  OcpCostAndGradient(ocp, x0, u, &grad);
  for (int i = 0; i < kNu * ocp.horizon_steps; i += 3) {
    const double h = 1e-2;
    std::vector<InputVector> up = u, um = u;
    up[i / kNu](i % kNu) += h;
    um[i / kNu](i % kNu) -= h;
    const double fd = (OcpCost(ocp, x0, up) - OcpCost(ocp, x0, um)) / (2 * h);
    EXPECT_NEAR(grad(i), fd, 1e-5 * std::abs(fd) + 1e-7)
        << "input " << i << ", mode " << ToString(ocp.mode) << ", re-taut " << ocp.retaut_stage;
  }
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
    ExpectGradientMatchesCentralDifferences(ocp, x0, u);
  }
}

// Largest entry of |a - dF/dx| and of |b - dF/du| with F's central differences (h = 1e-6 on the
// state, 1e-3 on rotor speeds of ~1e3 rad/s).
template <typename F>
std::pair<double, double> MaxCentralDifferenceError(const F& f, const StateVector& x,
                                                    const InputVector& u, const StateMatrix& a,
                                                    const InputMatrix& b) {
  double a_error = 0.0, b_error = 0.0;
  for (int i = 0; i < kNx; ++i) {
    StateVector xp = x, xm = x;
    xp(i) += 1e-6;
    xm(i) -= 1e-6;
    a_error = std::max(a_error, (a.col(i) - (f(xp, u) - f(xm, u)) / 2e-6).cwiseAbs().maxCoeff());
  }
  for (int i = 0; i < kNu; ++i) {
    InputVector up = u, um = u;
    up(i) += 1e-3;
    um(i) -= 1e-3;
    b_error = std::max(b_error, (b.col(i) - (f(x, up) - f(x, um)) / 2e-3).cwiseAbs().maxCoeff());
  }
  return {a_error, b_error};
}

// A slack state whose payload, thrown up, falls back past the cable's length inside the horizon.
StateVector ThrownUpPayload() {
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0.0, 0.0, 1.0);
  s.p_WL_W = Eigen::Vector3d(0.02, 0.0, 1.0 - 0.3);
  s.v_WL_W = Eigen::Vector3d(0.0, 0.0, 0.5);
  s.mode = CableMode::kSlack;
  return s.ToVector();
}

TEST(OcpTest, RetautPredictedWhereTheSlackRolloutReachesTheCable) {
  const Params params;
  const auto ref = HoverRef(params);
  Ocp ocp = BuildOcp(params, *ref, 0.0, CableMode::kSlack, 1.0);
  const StateVector x0 = ThrownUpPayload();
  const std::vector<InputVector> hover(ocp.horizon_steps,
                                       InputVector::Constant(params.HoverMotorSpeedRadps()));
  // payload 0.3 m below, rising at 0.5 m/s, in free fall: it is 0.5 m below again after
  // t = (0.5 + sqrt(0.25 + 2 g 0.2)) / g = 0.26 s (the quadrotor, lighter by the payload at
  // hover speeds, climbs 4 cm meanwhile), so the guard is reached in stage 3 (0.2-0.3 s)
  const int stage = PredictRetautStage(ocp, x0, hover);
  EXPECT_EQ(stage, 3);
  // a taut problem has no guard
  EXPECT_EQ(PredictRetautStage(BuildOcp(params, *ref, 0.0, CableMode::kTaut, 1.0), x0, hover), -1);
  // thrown up at 6 m/s the payload passes the vehicle (the model has no body) and reaches the
  // length above it: 0.70 m above at 0.2 s, moving away, so stage 2
  StateVector high = x0;
  high(StateIndex::kPayloadVel + 2) = 6.0;
  EXPECT_EQ(PredictRetautStage(ocp, high, hover), 2);

  // the schedule: slack stages before, taut from the guard on, references rebuilt for taut
  ScheduleRetaut(*ref, 0.0, stage, &ocp);
  EXPECT_EQ(ocp.StageMode(stage - 1), CableMode::kSlack);
  EXPECT_EQ(ocp.StageMode(stage), CableMode::kTaut);
  const Ocp taut = BuildOcp(params, *ref, 0.0, CableMode::kTaut, 1.0);
  EXPECT_EQ(ocp.u_ref[stage], taut.u_ref[stage]);
  EXPECT_NE(ocp.u_ref[stage - 1], taut.u_ref[stage - 1]);
  // moved one stage later, then cleared: the references are the slack problem's again
  const Ocp slack = BuildOcp(params, *ref, 0.0, CableMode::kSlack, 1.0);
  Ocp moved = ocp;
  ScheduleRetaut(*ref, 0.0, stage + 1, &moved);
  EXPECT_EQ(moved.u_ref[stage], slack.u_ref[stage]);
  EXPECT_EQ(moved.x_ref[stage + 1], taut.x_ref[stage + 1]);
  ScheduleRetaut(*ref, 0.0, -1, &moved);
  EXPECT_EQ(moved.retaut_stage, -1);
  for (int k = 0; k <= moved.horizon_steps; ++k) EXPECT_EQ(moved.x_ref[k], slack.x_ref[k]) << k;

  // the rollout meets the jump map at the guard: on the cable after it, no relative velocity
  // along it (the payload was moving away)
  std::vector<StateVector> x;
  OcpCost(ocp, x0, hover, &x);
  using I = StateIndex;
  const Eigen::Vector3d r = x[stage].segment<3>(I::kPayloadPos) - x[stage].segment<3>(I::kQuadPos);
  EXPECT_LE(r.norm(), params.cable_length_m + 1e-12);
  EXPECT_NEAR(
      (x[stage].segment<3>(I::kPayloadVel) - x[stage].segment<3>(I::kQuadVel)).dot(r.normalized()),
      0.0, 1e-12);
}

TEST(OcpTest, StepJacobiansThroughTheJumpMatchFiniteDifferences) {
  const Params params;
  const auto ref = HoverRef(params);
  Ocp ocp = BuildOcp(params, *ref, 0.0, CableMode::kSlack, 1.0);
  const StateVector x0 = ThrownUpPayload();
  const InputVector u = InputVector(1.02, 0.99, 1.01, 0.98) * params.HoverMotorSpeedRadps();
  // the stage entering the guard, from the state one stage before it
  ScheduleRetaut(*ref, 0.0, 3, &ocp);
  StateVector x = x0;
  for (int k = 0; k < 2; ++k) x = ocp.Step(k, x, u);
  StateVector x_next;
  StateMatrix a;
  InputMatrix b;
  ocp.StepJacobians(2, x, u, &x_next, &a, &b);
  EXPECT_LT((x_next - ocp.Step(2, x, u)).norm(), 1e-12);
  // central differences, h = 1e-6 on x ~ 1 and 1e-3 on u ~ 1e3: measured 6.3e-10 (x) and
  // 1.1e-12 (u); bounds about 10x above
  const auto step = [&ocp](const StateVector& xi, const InputVector& ui) {
    return ocp.Step(2, xi, ui);
  };
  const auto [max_a_error, max_b_error] = MaxCentralDifferenceError(step, x, u, a, b);
  std::printf("stage through the jump vs central differences: max error %.2e (x), %.2e (u)\n",
              max_a_error, max_b_error);
  EXPECT_LT(max_a_error, 1e-8);
  EXPECT_LT(max_b_error, 1e-11);
  // the cost gradient of the whole scheduled horizon matches finite differences too
  ExpectGradientMatchesCentralDifferences(ocp, x0, std::vector<InputVector>(ocp.horizon_steps, u));
}

}  // namespace
}  // namespace hpa
