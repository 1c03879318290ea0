// The OCP: its named residual terms, the camera transform, the perception dead zone and the soft
// limits (ocp_rollout_test.cc: the rollout, its gradient and the predicted re-taut).

#include "hpa/controller/ocp.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <string>
#include <utility>

namespace hpa {
namespace {

// Parameters with the payload camera on the cable's axis (5 cm below the attachment): the
// hanging payload is at the image centre, which the camera-term tests below take as their origin.
Params CameraOnCableAxis() {
  Params params;
  params.t_BC_B_m = Eigen::Vector3d(0.0, 0.0, -0.05);
  return params;
}

// Hover 1 m above the origin.
std::shared_ptr<Reference> HoverRef(const Params& params) {
  return MakeHoverReference(params, Eigen::Vector3d(0, 0, 1.0));
}

// The terms of the stage cost, by name, in residual order.
const std::vector<std::string> kTermNames = {
    "payload_position", "payload_velocity", "quad_position", "quad_velocity",
    "attitude",         "body_rate",        "input",         "perception",
    "tilt_limit",       "body_rate_limit"};

TEST(OcpTest, TermsTileTheResidualInListOrder) {
  std::vector<std::string> names;
  int next_row = 0;
  for (const OcpTerm& term : OcpTerms()) {
    names.emplace_back(term.name);
    EXPECT_EQ(term.offset, next_row) << term.name;
    EXPECT_GT(term.rows, 0) << term.name;
    ASSERT_NE(term.weight, nullptr) << term.name;
    ASSERT_NE(term.residual, nullptr) << term.name;
    EXPECT_EQ(FindOcpTerm(term.name), &term);
    next_row += term.rows;
  }
  EXPECT_EQ(next_row, kNr);
  EXPECT_EQ(names, kTermNames);
  EXPECT_EQ(FindOcpTerm("no_such_term"), nullptr);
}

// The stage residual is the terms' rows stacked at their offsets, and each term's stage weight
// follows its mode weight, the terminal factor and (for L_cam) the perception weight.
TEST(OcpTest, StageResidualStacksTheTermsWithTheirStageWeights) {
  const Params params;
  const auto ref = MakeLissajousReference(params, LissajousSpec());
  for (CableMode mode : {CableMode::kTaut, CableMode::kSlack}) {
    const Ocp ocp = BuildOcp(params, *ref, 2.5, mode, 2.0);
    StateVector x = HybridModel(params).HoverState(Eigen::Vector3d(0.1, 0.2, 1.4));
    x.segment<3>(StateIndex::kPayloadPos) += Eigen::Vector3d(0.2, -0.1, 0.05);
    x(StateIndex::kBodyRate) = 7.0;
    const InputVector u = 1.02 * ocp.u_ref[1];
    for (int k : {1, ocp.horizon_steps}) {
      ResidualVector r;
      ResidualStateJacobian r_x;
      ResidualInputJacobian r_u;
      StageResidual(ocp, k, x, u, &r, &r_x, &r_u);
      for (const OcpTerm& term : OcpTerms()) {
        Eigen::VectorXd r_term;
        Eigen::MatrixXd r_x_term, r_u_term;
        EvaluateOcpTerm(ocp, term, k, x, u, &r_term, &r_x_term, &r_u_term);
        // the same code path: bit-identical rows
        EXPECT_EQ(r.segment(term.offset, term.rows), r_term) << term.name;
        EXPECT_EQ(r_x.middleRows(term.offset, term.rows), r_x_term) << term.name;
        EXPECT_EQ(r_u.middleRows(term.offset, term.rows), r_u_term) << term.name;
      }
      const bool terminal = k == ocp.horizon_steps;
      const double factor = terminal ? ocp.weights.terminal_factor : 1.0;
      const StateVector& q = mode == CableMode::kTaut ? ocp.weights.q_load : ocp.weights.q_quad;
      EXPECT_EQ(OcpTermStageWeight(ocp, *FindOcpTerm("quad_position"), k),
                factor * q.segment<3>(StateIndex::kQuadPos));
      EXPECT_EQ(OcpTermStageWeight(ocp, *FindOcpTerm("input"), k),
                terminal ? InputVector::Zero() : ocp.weights.r_input);
      const Eigen::Vector2d& q_cam =
          mode == CableMode::kTaut ? ocp.weights.q_cam_per_m2 : ocp.weights.q_cam_slack_per_m2;
      EXPECT_EQ(OcpTermStageWeight(ocp, *FindOcpTerm("perception"), k), factor * 2.0 * q_cam);
      EXPECT_EQ(OcpTermStageWeight(ocp, *FindOcpTerm("tilt_limit"), k)(0), ocp.weights.tilt_weight);
    }
  }
}

// perception_weight 0 switches L_cam off: its rows carry zero weight and stay zero however far
// the payload is from the image centre; the other terms do not notice.
TEST(OcpTest, PerceptionTermIsZeroWeightedAtZeroPerceptionWeight) {
  const Params params;
  const OcpTerm& perception = *FindOcpTerm("perception");
  for (CableMode mode : {CableMode::kTaut, CableMode::kSlack}) {
    const Ocp off = BuildOcp(params, *HoverRef(params), 0.0, mode, 0.0);
    const Ocp on = BuildOcp(params, *HoverRef(params), 0.0, mode, 1.0);
    StateVector x = HybridModel(params).HoverState(Eigen::Vector3d(0, 0, 1.5));
    x.segment<3>(StateIndex::kPayloadPos) += Eigen::Vector3d(0.3, -0.25, 0.1);  // far off centre
    for (int k : {0, off.horizon_steps}) {
      EXPECT_TRUE(OcpTermStageWeight(off, perception, k).isZero(0.0)) << ToString(mode);
      EXPECT_TRUE(OcpTermStageWeight(on, perception, k).minCoeff() > 0.0) << ToString(mode);
      ResidualVector r_off, r_on;
      ResidualStateJacobian r_x_off, r_x_on;
      StageResidual(off, k, x, off.u_ref[0], &r_off, &r_x_off, nullptr);
      StageResidual(on, k, x, on.u_ref[0], &r_on, &r_x_on, nullptr);
      EXPECT_TRUE(r_off.segment(perception.offset, perception.rows).isZero(0.0));
      EXPECT_TRUE(r_x_off.middleRows(perception.offset, perception.rows).isZero(0.0));
      // taut (no dead zone): the same offset costs with weight 1
      if (mode == CableMode::kTaut) {
        EXPECT_GT(r_on.segment(perception.offset, perception.rows).norm(), 0.0);
      }
      // every other row is unchanged
      for (const OcpTerm& term : OcpTerms()) {
        if (&term == &perception) continue;
        EXPECT_EQ(r_off.segment(term.offset, term.rows), r_on.segment(term.offset, term.rows))
            << term.name;
      }
    }
  }
}

// Each term's Jacobians against central differences of its own residual, by name, in both
// modes, at a stage and at the terminal, with every term active: payload off the image centre
// (beyond the slack dead zone, and beyond the cable's length: the slack L_cam sees it on the
// cable's sphere), 50 deg tilt (limit 45), body rates 7 and -6.5 rad/s (limit 6).
// Also the paper's L_cam at the state's attitude (automatic differentiation in the quaternion).
TEST(OcpTest, TermJacobiansMatchFiniteDifferences) {
  const Params params;
  const auto ref = MakeLissajousReference(params, LissajousSpec());
  SystemState s;
  s.FromVector(HybridModel(params).HoverState(Eigen::Vector3d(0.1, 0.2, 1.4)));
  s.p_WL_W = s.p_WQ_W + Eigen::Vector3d(0.45, -0.35, -0.3);
  s.q_WB = Eigen::AngleAxisd(50 * M_PI / 180, Eigen::Vector3d(1, 2, 0).normalized());
  s.w_B = Eigen::Vector3d(7.0, -6.5, 0.5);
  const StateVector x = s.ToVector();
  double max_error_x = 0.0, max_error_u = 0.0;
  for (bool cam_at_reference : {true, false}) {
    // taut, slack, and slack with the payload held (no free fall in L_cam, its own dead zone)
    const std::pair<CableMode, bool> cases[] = {
        {CableMode::kTaut, false}, {CableMode::kSlack, false}, {CableMode::kSlack, true}};
    for (const auto& [mode, held] : cases) {
      OcpWeights weights = OcpWeights::Tuned();
      weights.cam_at_reference_attitude = cam_at_reference;
      Ocp ocp = BuildOcp(params, *ref, 2.5, mode, 2.0, weights);
      ocp.payload_supported = held;
      SystemState level = s;  // dead zone from the depth of the payload below a level body
      level.q_WB.setIdentity();
      SetCameraDeadzone(level, &ocp);
      const InputVector u = ocp.u_ref[1].cwiseProduct(InputVector(1.03, 0.98, 1.01, 0.97));
      for (const std::string& name : kTermNames) {
        const OcpTerm* term = FindOcpTerm(name);
        ASSERT_NE(term, nullptr) << name;
        for (int k : {1, ocp.horizon_steps}) {
          Eigen::VectorXd r, r_p, r_m;
          Eigen::MatrixXd r_x, r_u;
          EvaluateOcpTerm(ocp, *term, k, x, u, &r, &r_x, &r_u);
          ASSERT_EQ(r.size(), term->rows);
          // every weighted term is active at stage 1 (slack: the payload terms weigh 0)
          if (k < ocp.horizon_steps && OcpTermStageWeight(ocp, *term, k).maxCoeff() > 0.0) {
            EXPECT_GT(r.norm(), 0.0) << name << " inactive, mode " << ToString(mode) << " held "
                                     << held;
          }
          // h: 1e-6 on unit-scale states, 1e-3 rad/s on ~1e3 rad/s rotor speeds. Measured max
          // error 9.5e-9 in d/dx (truncation and rounding of the nonlinear terms), 4.7e-14 in
          // d/du (the input term is linear: rounding only); bounds about 10x above
          for (int j = 0; j < kNx; ++j) {
            StateVector x_p = x, x_m = x;
            x_p(j) += 1e-6;
            x_m(j) -= 1e-6;
            EvaluateOcpTerm(ocp, *term, k, x_p, u, &r_p, nullptr, nullptr);
            EvaluateOcpTerm(ocp, *term, k, x_m, u, &r_m, nullptr, nullptr);
            const double error = ((r_p - r_m) / 2e-6 - r_x.col(j)).cwiseAbs().maxCoeff();
            max_error_x = std::max(max_error_x, error);
            EXPECT_LT(error, 1e-7) << name << " d/dx_" << j << " mode " << ToString(mode)
                                   << " held " << held;
          }
          for (int j = 0; j < kNu; ++j) {
            InputVector u_p = u, u_m = u;
            u_p(j) += 1e-3;
            u_m(j) -= 1e-3;
            EvaluateOcpTerm(ocp, *term, k, x, u_p, &r_p, nullptr, nullptr);
            EvaluateOcpTerm(ocp, *term, k, x, u_m, &r_m, nullptr, nullptr);
            const double error = ((r_p - r_m) / 2e-3 - r_u.col(j)).cwiseAbs().maxCoeff();
            max_error_u = std::max(max_error_u, error);
            EXPECT_LT(error, 5e-13) << name << " d/du_" << j << " mode " << ToString(mode);
          }
        }
      }
    }
  }
  std::printf("term Jacobians vs central differences: max error d/dx %.2e, d/du %.2e\n",
              max_error_x, max_error_u);
}

TEST(OcpTest, CameraTransformOfHangingPayload) {
  const Params params = CameraOnCableAxis();
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
  const Params params = CameraOnCableAxis();
  const Ocp ocp = BuildOcp(params, *HoverRef(params), 0.0, CableMode::kSlack, 2.0);
  SystemState s;
  s.FromVector(HybridModel(params).HoverState(Eigen::Vector3d(0, 0, 1.5)));
  s.p_WL_W = s.p_WQ_W + Eigen::Vector3d(0.3, 0.1, -0.2);  // held beside, cable slack
  s.q_WB = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 1, 0).normalized());
  ResidualVector r;
  ResidualStateJacobian r_x;
  ResidualInputJacobian r_u;
  StageResidual(ocp, 1, s.ToVector(), ocp.u_ref[1], &r, &r_x, &r_u);
  const int kCamRow = FindOcpTerm("perception")->offset;
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
  const Params params = CameraOnCableAxis();
  Ocp ocp = BuildOcp(params, *HoverRef(params), 0.0, CableMode::kSlack, 1.0);
  SystemState s;
  s.FromVector(HybridModel(params).HoverState(Eigen::Vector3d(0, 0, 1.5)));
  // payload held 0.3 m below the body origin: depth 0.25 m below the lens
  s.p_WL_W = s.p_WQ_W + Eigen::Vector3d(0.1, 0.05, -0.3);
  SetCameraDeadzone(s, &ocp);
  const double f = params.CameraFocalPx();
  const Eigen::Vector2d dead =
      ocp.weights.cam_slack_deadzone_fraction * 0.25 * Eigen::Vector2d(640.0 / f, 360.0 / f);
  EXPECT_TRUE(ocp.cam_slack_deadzone_m.isApprox(dead, 1e-12));
  const int kCamRow = FindOcpTerm("perception")->offset;
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
  // a held payload has its own, tighter zone: the first offset above is beyond it
  ocp.payload_supported = true;
  s.p_WL_W = s.p_WQ_W + Eigen::Vector3d(0.1, 0.05, -0.3);
  SetCameraDeadzone(s, &ocp);
  const Eigen::Vector2d held_dead =
      ocp.weights.cam_held_deadzone_fraction * 0.25 * Eigen::Vector2d(640.0 / f, 360.0 / f);
  EXPECT_TRUE(ocp.cam_slack_deadzone_m.isApprox(held_dead, 1e-12));
  StageResidual(ocp, 1, s.ToVector(), ocp.u_ref[1], &r, &r_x, &r_u);
  EXPECT_NEAR(r(kCamRow), scale * (0.1 - held_dead.x()), 1e-12);
}

// The slack camera term follows each stage's predicted payload: a payload thrown down fast
// passes the cable's length inside the horizon. L_cam sees every stage's payload no further than
// the cable's sphere (in the direction of the free fall), and sizes each stage's dead zone from
// that payload's own depth, not from the current one.
TEST(OcpTest, SlackCameraTermSeesEachStagesPayloadOnTheCablesSphere) {
  const Params params = CameraOnCableAxis();
  Ocp ocp = BuildOcp(params, *HoverRef(params), 0.0, CableMode::kSlack, 1.0);
  SystemState s;
  s.FromVector(HybridModel(params).HoverState(Eigen::Vector3d(0, 0, 1.5)));
  s.p_WL_W = s.p_WQ_W + Eigen::Vector3d(0.05, 0.0, -0.3);
  s.v_WL_W = Eigen::Vector3d(0.4, 0.0, -1.0);  // past the cable's length at stage 2
  SetCameraDeadzone(s, &ocp);
  const std::vector<InputVector> u(ocp.horizon_steps, ocp.u_ref[0]);
  SetCameraDeadzonesAlong(s.ToVector(), u, &ocp);
  ASSERT_EQ(ocp.cam_slack_deadzone_stage_m.size(), static_cast<size_t>(ocp.horizon_steps + 1));
  EXPECT_TRUE(ocp.CamSlackDeadzone(0).isApprox(ocp.cam_slack_deadzone_m, 1e-12));
  std::vector<StateVector> x;
  OcpCost(ocp, s.ToVector(), u, &x);
  const double l = params.cable_length_m;
  int beyond = 0;
  for (int k = 1; k <= ocp.horizon_steps; ++k) {
    const Eigen::Vector3d d_W =
        x[k].segment<3>(StateIndex::kPayloadPos) - x[k].segment<3>(StateIndex::kQuadPos);
    beyond += d_W.norm() > l ? 1 : 0;
    // the payload L_cam sees: on the sphere in the free fall's direction once beyond it
    StateVector seen = x[k];
    seen.segment<3>(StateIndex::kPayloadPos) =
        x[k].segment<3>(StateIndex::kQuadPos) + std::min(1.0, l / d_W.norm()) * d_W;
    StateVector seen_level = seen;  // at the stage's reference attitude (level hover)
    seen_level.segment<4>(StateIndex::kQuat) = ocp.x_ref[k].segment<4>(StateIndex::kQuat);
    const Eigen::Vector3d p_C = CostPayloadInCamera(ocp, k, x[k]);
    EXPECT_TRUE(p_C.isApprox(PayloadInCamera(ocp, seen_level), 1e-12)) << "stage " << k;
    EXPECT_LE(p_C.norm(), l + 0.1) << "stage " << k;  // camera 5 cm below the attachment
    EXPECT_TRUE(ocp.CamSlackDeadzone(k).isApprox(
        ocp.weights.cam_slack_deadzone_fraction * p_C.z() * ocp.camera_tan_half_fov, 1e-12))
        << "stage " << k;
  }
  // the fall passes the cable's length after a few of the 10 stages: both kinds are covered
  EXPECT_GE(beyond, 5);
  EXPECT_LE(beyond, 9);
  // taut problems have no per-stage slack dead zone
  Ocp taut = BuildOcp(params, *HoverRef(params), 0.0, CableMode::kTaut, 1.0);
  SetCameraDeadzonesAlong(s.ToVector(), u, &taut);
  EXPECT_TRUE(taut.cam_slack_deadzone_stage_m.empty());
}

TEST(OcpTest, SoftLimitsArePenalisedOnlyBeyondTheirBounds) {
  const Params params;
  const Ocp ocp = BuildOcp(params, *HoverRef(params), 0.0, CableMode::kTaut, 1.0);
  const HybridModel model(params);
  const InputVector u = ocp.u_ref[0];
  ResidualVector r;
  const int kTiltRow = FindOcpTerm("tilt_limit")->offset;
  const int kRateRow = FindOcpTerm("body_rate_limit")->offset;
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

}  // namespace
}  // namespace hpa
