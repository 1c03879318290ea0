// The hand-derived derivatives (exact_derivatives.h, the perception term's attitude Jacobian)
// against the forward-mode AD path of HybridModel and against central differences.
//
// Tolerances:
// - against AD: both evaluate the same closed-form derivative in double precision, in a different
//   operation order, so they agree to rounding: a few ulps of the largest entry. The test allows
//   1e-13 relative to max(1, largest |entry|) (about 450 ulps, room for the RK4 chain's
//   accumulation over four stages).
// - against central differences with step h = 1e-6 (1 + |x_i|): truncation error h^2 |f'''| / 6
//   (below 1e-11 here) and cancellation eps |f| / h (values up to order 1e2: up to about 2e-8,
//   relative to entries of order 1e1 and more); the test allows 1e-7 relative to max(1, largest
//   |entry|).

#include "exact_derivatives.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <random>
#include <unsupported/Eigen/AutoDiff>

#include "hpa/controller/ocp.h"
#include "hpa/models/rotor_model.h"
#include "ocp_internal.h"

namespace hpa {
namespace {

using I = StateIndex;
constexpr double kAdTolerance = 1e-13;
constexpr double kFdTolerance = 1e-7;
constexpr double kFdStep = 1e-6;

// Largest |difference| relative to max(1, largest |entry| of the reference).
template <typename A, typename B>
double RelativeError(const A& actual, const B& expected) {
  return (actual - expected).cwiseAbs().maxCoeff() / std::max(1.0, expected.cwiseAbs().maxCoeff());
}

// A state near hover with random velocities, a tilted attitude, a body rate and a cable length
// off l (taut flow's Baumgarte terms active), and rotor speeds around hover.
void RandomStateAndInput(const Params& params, std::mt19937* rng, StateVector* x, InputVector* u) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const auto random3 = [&]() { return Eigen::Vector3d(unit(*rng), unit(*rng), unit(*rng)); };
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0.3, -0.2, 1.5) + 0.2 * random3();
  const Eigen::Vector3d dir = (Eigen::Vector3d(0, 0, -1) + 0.4 * random3()).normalized();
  s.p_WL_W = s.p_WQ_W + (params.cable_length_m + 0.02 * unit(*rng)) * dir;
  s.v_WQ_W = random3();
  s.v_WL_W = s.v_WQ_W + 0.8 * random3();
  s.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * unit(*rng), random3().normalized()));
  s.w_B = 2.0 * random3();
  *x = s.ToVector();
  *u = InputVector::Constant(params.HoverMotorSpeedRadps()) +
       100.0 * InputVector(unit(*rng), unit(*rng), unit(*rng), unit(*rng));
}

// Central differences of f: R^19 x R^4 -> R^m in (x, u), m x 23.
template <typename F>
Eigen::MatrixXd CentralDifferences(const F& f, const StateVector& x, const InputVector& u) {
  Eigen::MatrixXd j(f(x, u).size(), kNxu);
  for (int i = 0; i < kNxu; ++i) {
    StateVector xp = x, xm = x;
    InputVector up = u, um = u;
    double& vp = i < kNx ? xp(i) : up(i - kNx);
    double& vm = i < kNx ? xm(i) : um(i - kNx);
    const double h = kFdStep * (1.0 + std::abs(vp));
    vp += h;
    vm -= h;
    j.col(i) = (f(xp, up) - f(xm, um)) / (2.0 * h);
  }
  return j;
}

TEST(ExactDerivativesTest, FlowJacobianMatchesAutoDiff) {
  const Params params;
  const HybridModel model(params);
  std::mt19937 rng(1);
  for (CableMode mode : {CableMode::kTaut, CableMode::kSlack}) {
    for (int trial = 0; trial < 20; ++trial) {
      StateVector x;
      InputVector u;
      RandomStateAndInput(params, &rng, &x, &u);
      StateVector x_dot;
      StateMatrix a_ad, a;
      InputMatrix b_ad, b;
      model.DerivativeJacobians(x, u, mode, &x_dot, &a_ad, &b_ad);
      FlowJacobian j;
      EvaluateFlowJacobian(params, AllocationMatrix(params), x, u, mode, &j);
      DenseFlowJacobian(j, &a, &b);
      EXPECT_LT(RelativeError(a, a_ad), kAdTolerance) << ToString(mode) << " trial " << trial;
      EXPECT_LT(RelativeError(b, b_ad), kAdTolerance) << ToString(mode) << " trial " << trial;
    }
  }
}

// FlowJacobianMatrix places the blocks that ApplyFlowJacobian of the identity computes, and
// EvaluateRotorJacobian's part is the one EvaluateFlowJacobian from u uses: bit for bit (the
// RK4 step Jacobians take k1 and the rotor part that way).
TEST(ExactDerivativesTest, FlowJacobianMatrixIsTheFlowJacobianOfTheIdentity) {
  const Params params;
  std::mt19937 rng(3);
  for (CableMode mode : {CableMode::kTaut, CableMode::kSlack}) {
    for (int trial = 0; trial < 20; ++trial) {
      StateVector x;
      InputVector u;
      RandomStateAndInput(params, &rng, &x, &u);
      FlowJacobian j, j_rotor;
      EvaluateFlowJacobian(params, AllocationMatrix(params), x, u, mode, &j);
      EvaluateFlowJacobian(params, EvaluateRotorJacobian(params, AllocationMatrix(params), u), x,
                           mode, &j_rotor);
      StepSensitivity k_applied, k_placed, k_rotor;
      ApplyFlowJacobian(j, StepSensitivity::Identity(), &k_applied);
      FlowJacobianMatrix(j, &k_placed);
      FlowJacobianMatrix(j_rotor, &k_rotor);
      EXPECT_EQ(k_placed, k_applied) << ToString(mode) << " trial " << trial;
      EXPECT_EQ(k_rotor, k_placed) << ToString(mode) << " trial " << trial;
    }
  }
}

TEST(ExactDerivativesTest, StepJacobiansMatchAutoDiffAndCentralDifferences) {
  const Params params;
  const HybridModel model(params);
  std::mt19937 rng(2);
  for (CableMode mode : {CableMode::kTaut, CableMode::kSlack}) {
    for (int trial = 0; trial < 10; ++trial) {
      StateVector x;
      InputVector u;
      RandomStateAndInput(params, &rng, &x, &u);
      StateVector y_ad, y;
      StateMatrix a_ad, a;
      InputMatrix b_ad, b;
      model.StepJacobians(x, u, mode, kOcpStageDtS, &y_ad, &a_ad, &b_ad);
      ExactStepJacobians(model, x, u, mode, kOcpStageDtS, &y, &a, &b);
      // the value is HybridModel::Step's, to the bit
      const StateVector y_step = model.Step(x, u, mode, kOcpStageDtS);
      for (int i = 0; i < kNx; ++i) EXPECT_EQ(y(i), y_step(i)) << i;
      EXPECT_LT(RelativeError(a, a_ad), kAdTolerance) << ToString(mode) << " trial " << trial;
      EXPECT_LT(RelativeError(b, b_ad), kAdTolerance) << ToString(mode) << " trial " << trial;
      const auto fd = CentralDifferences(
          [&](const StateVector& xs, const InputVector& us) {
            return model.Step(xs, us, mode, kOcpStageDtS);
          },
          x, u);
      EXPECT_LT(RelativeError(a, fd.leftCols<kNx>()), kFdTolerance) << ToString(mode);
      EXPECT_LT(RelativeError(b, fd.rightCols<kNu>()), kFdTolerance) << ToString(mode);
    }
  }
}

// Every branch of the jump map: cable too long / too short / in the taut band, payload moving
// away (inelastic collision) or approaching (no impulse).
TEST(ExactDerivativesTest, JumpJacobianMatchesAutoDiffAndCentralDifferencesInEveryBranch) {
  const Params params;
  const HybridModel model(params);
  const double l = params.cable_length_m;
  std::mt19937 rng(3);
  for (double length_m : {l + 0.1, l - 0.2, l - 0.5 * params.slack_epsilon_m}) {
    for (double v_away_mps : {0.7, -0.7}) {
      StateVector x;
      InputVector u;
      RandomStateAndInput(params, &rng, &x, &u);
      const Eigen::Vector3d xi =
          (x.segment<3>(I::kPayloadPos) - x.segment<3>(I::kQuadPos)).normalized();
      x.segment<3>(I::kPayloadPos) = x.segment<3>(I::kQuadPos) + length_m * xi;
      x.segment<3>(I::kPayloadVel) =
          x.segment<3>(I::kQuadVel) + v_away_mps * xi + 0.3 * xi.unitOrthogonal();
      StateMatrix j_ad, j;
      const StateVector y_ad = model.ProjectToTautJacobian(x, &j_ad);
      const StateVector y = ExactJumpJacobian(model, x, &j);
      // the value is ProjectToTaut's to the bit (AD's norm sums in another order: rounding)
      EXPECT_EQ(y, model.ProjectToTaut(x));
      EXPECT_LT(RelativeError(y, y_ad), kAdTolerance);
      EXPECT_LT(RelativeError(j, j_ad), kAdTolerance) << length_m << " " << v_away_mps;
      const auto fd = CentralDifferences(
          [&](const StateVector& xs, const InputVector&) { return model.ProjectToTaut(xs); }, x, u);
      EXPECT_LT(RelativeError(j, fd.leftCols<kNx>()), kFdTolerance)
          << length_m << " " << v_away_mps;
    }
  }
}

// Ocp::StepJacobians (exact path) against the AD chain model Jacobians -> jump map Jacobian at a
// scheduled re-taut.
TEST(ExactDerivativesTest, OcpStepJacobiansThroughTheJumpMatchTheAutoDiffChain) {
  const Params params;
  const auto ref = MakeHoverReference(params, Eigen::Vector3d(0, 0, 1.0));
  Ocp ocp = BuildOcp(params, *ref, 0.0, CableMode::kSlack, 1.0);
  ScheduleRetaut(*ref, 0.0, 1, &ocp);
  std::mt19937 rng(4);
  StateVector x;
  InputVector u;
  RandomStateAndInput(params, &rng, &x, &u);
  x.segment<3>(I::kPayloadVel) += 0.5 * (x.segment<3>(I::kPayloadPos) - x.segment<3>(I::kQuadPos));
  StateVector y, y_ad;
  StateMatrix a, a_ad, jump;
  InputMatrix b, b_ad;
  ocp.StepJacobians(0, x, u, &y, &a, &b);
  ocp.model->StepJacobians(x, u, CableMode::kSlack, ocp.stage_dt_s, &y_ad, &a_ad, &b_ad);
  y_ad = ocp.model->ProjectToTautJacobian(y_ad, &jump);
  EXPECT_EQ(y, ocp.Step(0, x, u));
  EXPECT_LT(RelativeError(y, y_ad), kAdTolerance);
  EXPECT_LT(RelativeError(a, (jump * a_ad).eval()), kAdTolerance);
  EXPECT_LT(RelativeError(b, (jump * b_ad).eval()), kAdTolerance);
}

// L_cam at the state's attitude (the paper's literal form): the hand-derived d p_C / d q against
// AD of CameraPoint, and the whole stage residual Jacobian against central differences.
TEST(ExactDerivativesTest, PerceptionAttitudeJacobianMatchesAutoDiffAndCentralDifferences) {
  Params params;
  params.t_BC_B_m = Eigen::Vector3d(0.02, -0.01, -0.05);
  const auto ref = MakeHoverReference(params, Eigen::Vector3d(0, 0, 1.0));
  OcpWeights weights = OcpWeights::Tuned();
  weights.cam_at_reference_attitude = false;
  std::mt19937 rng(5);
  for (CableMode mode : {CableMode::kTaut, CableMode::kSlack}) {
    Ocp ocp = BuildOcp(params, *ref, 0.0, mode, 3.0, weights);
    ocp.cam_slack_deadzone_m = Eigen::Vector2d(0.01, 0.01);
    StateVector x;
    InputVector u;
    RandomStateAndInput(params, &rng, &x, &u);
    const Eigen::Vector3d d_W = x.segment<3>(I::kPayloadPos) - x.segment<3>(I::kQuadPos);
    const Eigen::Vector4d q = x.segment<4>(I::kQuat);
    using Ad = Eigen::AutoDiffScalar<Eigen::Vector4d>;
    Eigen::Matrix<Ad, 4, 1> q_ad;
    for (int i = 0; i < 4; ++i) q_ad(i) = Ad(q(i), 4, i);
    const Eigen::Matrix<Ad, 3, 1> p_ad = ocp_internal::CameraPoint<Ad>(ocp, d_W, q_ad);
    Eigen::Matrix<double, 3, 4> p_q_ad;
    for (int i = 0; i < 3; ++i) p_q_ad.row(i) = p_ad(i).derivatives().transpose();
    EXPECT_LT(RelativeError(ocp_internal::CameraPointQuatJacobian(ocp, d_W, q), p_q_ad),
              kAdTolerance);
    ResidualVector r;
    ResidualStateJacobian r_x;
    ResidualInputJacobian r_u;
    StageResidual(ocp, 2, x, u, &r, &r_x, &r_u);
    const auto fd = CentralDifferences(
        [&](const StateVector& xs, const InputVector& us) {
          ResidualVector rs;
          StageResidual(ocp, 2, xs, us, &rs, nullptr, nullptr);
          return rs;
        },
        x, u);
    EXPECT_LT(RelativeError(r_x, fd.leftCols<kNx>()), kFdTolerance) << ToString(mode);
    EXPECT_LT(RelativeError(r_u, fd.rightCols<kNu>()), kFdTolerance) << ToString(mode);
  }
}

}  // namespace
}  // namespace hpa
