#include "hpa/models/hybrid_model.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "hpa/models/rotor_model.h"

namespace hpa {
namespace {

// A swinging, rotating, accelerating taut state (cable length exactly l).
StateVector SwingingState(const Params& p) {
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0.1, -0.2, 1.5);
  const Eigen::Vector3d xi = Eigen::Vector3d(0.3, -0.2, -1.0).normalized();
  s.p_WL_W = s.p_WQ_W + p.cable_length_m * xi;
  s.v_WQ_W = Eigen::Vector3d(0.5, 0.2, -0.1);
  const Eigen::Vector3d xi_dot = Eigen::Vector3d(0.4, 0.7, 0.0).cross(xi);
  s.v_WL_W = s.v_WQ_W + p.cable_length_m * xi_dot;
  s.q_WB = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 0.5).normalized());
  s.w_B = Eigen::Vector3d(0.5, -0.3, 0.2);
  return s.ToVector();
}

InputVector SomeInput(const Params& p) {
  return InputVector(1.05, 0.95, 1.02, 0.98) * p.HoverMotorSpeedRadps();
}

// Central differences of f around (x, u); step 1e-6 relative to a value of order 1 to 1e3.
template <typename F>
void FiniteDifferences(const F& f, const StateVector& x, const InputVector& u, StateMatrix* a,
                       InputMatrix* b) {
  for (int i = 0; i < kNx; ++i) {
    const double h = 1e-6;
    StateVector xp = x, xm = x;
    xp(i) += h;
    xm(i) -= h;
    a->col(i) = (f(xp, u) - f(xm, u)) / (2 * h);
  }
  for (int i = 0; i < kNu; ++i) {
    const double h = 1e-3;  // rotor speeds are ~1e3 rad/s
    InputVector up = u, um = u;
    up(i) += h;
    um(i) -= h;
    b->col(i) = (f(x, up) - f(x, um)) / (2 * h);
  }
}

class HybridModelJacobianTest : public testing::TestWithParam<CableMode> {};

TEST_P(HybridModelJacobianTest, ContinuousJacobiansMatchFiniteDifferences) {
  const Params p;
  const HybridModel model(p);
  const StateVector x = SwingingState(p);
  const InputVector u = SomeInput(p);
  StateVector x_dot;
  StateMatrix a, a_fd;
  InputMatrix b, b_fd;
  model.DerivativeJacobians(x, u, GetParam(), &x_dot, &a, &b);
  FiniteDifferences([&](const StateVector& xx,
                        const InputVector& uu) { return model.Derivative(xx, uu, GetParam()); },
                    x, u, &a_fd, &b_fd);
  EXPECT_LT((x_dot - model.Derivative(x, u, GetParam())).norm(), 1e-12);
  // central differences with h = 1e-6 on O(100) second derivatives: truncation ~1e-10,
  // round-off ~1e-16 * |f| / h ~ 1e-8; bound 1e-6 leaves 100x margin
  EXPECT_LT((a - a_fd).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LT((b - b_fd).cwiseAbs().maxCoeff(), 1e-6);
}

TEST_P(HybridModelJacobianTest, DiscreteJacobiansMatchFiniteDifferences) {
  const Params p;
  const HybridModel model(p);
  const StateVector x = SwingingState(p);
  const InputVector u = SomeInput(p);
  const double dt_s = 0.1;  // the MPC's stage length
  StateVector x_next;
  StateMatrix a, a_fd;
  InputMatrix b, b_fd;
  model.StepJacobians(x, u, GetParam(), dt_s, &x_next, &a, &b);
  FiniteDifferences([&](const StateVector& xx,
                        const InputVector& uu) { return model.Step(xx, uu, GetParam(), dt_s); },
                    x, u, &a_fd, &b_fd);
  EXPECT_LT((x_next - model.Step(x, u, GetParam(), dt_s)).norm(), 1e-12);
  EXPECT_LT((a - a_fd).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LT((b - b_fd).cwiseAbs().maxCoeff(), 1e-6);
}

INSTANTIATE_TEST_SUITE_P(BothModes, HybridModelJacobianTest,
                         testing::Values(CableMode::kTaut, CableMode::kSlack));

TEST(HybridModelTest, HoverIsAnEquilibriumWithTensionMLg) {
  const Params p;
  const HybridModel model(p);
  const StateVector x = model.HoverState(Eigen::Vector3d(0, 0, 1.2));
  const InputVector u = InputVector::Constant(p.HoverMotorSpeedRadps());
  EXPECT_LT(model.Derivative(x, u, CableMode::kTaut).norm(), 1e-9);
  EXPECT_NEAR(model.TautTensionN(x, u), p.payload_mass_kg * p.gravity_mps2, 1e-9);
  // slack: the payload falls at g, the quadrotor rises (thrust carries both masses)
  const StateVector x_dot = model.Derivative(x, u, CableMode::kSlack);
  EXPECT_NEAR(x_dot(StateIndex::kPayloadVel + 2), -p.gravity_mps2, 1e-12);
  EXPECT_NEAR(x_dot(StateIndex::kQuadVel + 2), p.HoverThrustN() / p.quad_mass_kg - p.gravity_mps2,
              1e-9);
}

TEST(HybridModelTest, QuaternionStaysUnitAndCableLengthHolds) {
  const Params p;
  const HybridModel model(p);
  StateVector x = SwingingState(p);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> jitter(0.9, 1.1);
  double max_length_error_m = 0.0;
  for (int k = 0; k < 2000; ++k) {  // 20 s at 10 ms
    InputVector u;
    for (int i = 0; i < kNu; ++i) u(i) = p.HoverMotorSpeedRadps() * jitter(rng);
    x = model.Step(x, u, CableMode::kTaut, 0.01);
    ASSERT_NEAR(x.segment<4>(StateIndex::kQuat).norm(), 1.0, 1e-12);
    const double d =
        (x.segment<3>(StateIndex::kPayloadPos) - x.segment<3>(StateIndex::kQuadPos)).norm();
    max_length_error_m = std::max(max_length_error_m, std::abs(d - p.cable_length_m));
  }
  // Baumgarte terms hold the constraint; measured drift ~1e-6 m, bound 1 mm
  EXPECT_LT(max_length_error_m, 1e-3);
}

TEST(HybridModelTest, Rk4OneStepErrorAgainstFineIntegration) {
  const Params p;
  const HybridModel model(p);
  const StateVector x = SwingingState(p);
  const InputVector u = SomeInput(p);
  for (CableMode mode : {CableMode::kTaut, CableMode::kSlack}) {
    // reference: 1000 RK4 substeps of 0.1 ms over the MPC's 0.1 s stage
    StateVector x_ref = x;
    for (int k = 0; k < 1000; ++k) x_ref = model.Step(x_ref, u, mode, 1e-4);
    const StateVector x_one = model.Step(x, u, mode, 0.1);
    const double pos_error_m = std::max((x_one - x_ref).segment<3>(StateIndex::kPayloadPos).norm(),
                                        (x_one - x_ref).segment<3>(StateIndex::kQuadPos).norm());
    RecordProperty(std::string("rk4_stage_pos_error_m_") + ToString(mode),
                   std::to_string(pos_error_m));
    // measured 1e-5 (taut) and 1e-6 (slack) m; 1 mm bound is what the MPC needs over a stage
    EXPECT_LT(pos_error_m, 1e-3) << ToString(mode);
  }
}

TEST(HybridModelTest, ProjectToTautIsTheInelasticCollision) {
  const Params p;
  const HybridModel model(p);
  // payload 0.41 m below (short of the taut band) and falling away from the quadrotor
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0, 0, 1.2);
  s.p_WL_W = Eigen::Vector3d(0.1, 0, 0.8);
  s.v_WQ_W = Eigen::Vector3d(0.2, 0, 0.1);
  s.v_WL_W = Eigen::Vector3d(0.3, 0.1, -2.0);
  const StateVector x = s.ToVector();
  const StateVector y = model.ProjectToTaut(x);
  using I = StateIndex;
  const Eigen::Vector3d r = y.segment<3>(I::kPayloadPos) - y.segment<3>(I::kQuadPos);
  // moved only to the edge of the taut band, not to the full length
  EXPECT_NEAR(r.norm(), p.cable_length_m - p.slack_epsilon_m, 1e-12);
  const Eigen::Vector3d xi = r.normalized();
  const double m = p.quad_mass_kg, m_L = p.payload_mass_kg;
  // momentum and centre of mass kept, no relative velocity along the cable
  const Eigen::Vector3d momentum = m * s.v_WQ_W + m_L * s.v_WL_W;
  EXPECT_LT((m * y.segment<3>(I::kQuadVel) + m_L * y.segment<3>(I::kPayloadVel) - momentum).norm(),
            1e-12);
  EXPECT_LT((m * y.segment<3>(I::kQuadPos) + m_L * y.segment<3>(I::kPayloadPos) -
             (m * s.p_WQ_W + m_L * s.p_WL_W))
                .norm(),
            1e-12);
  EXPECT_NEAR((y.segment<3>(I::kPayloadVel) - y.segment<3>(I::kQuadVel)).dot(xi), 0.0, 1e-12);
  // a state already on the manifold is a fixed point
  const StateVector h = model.HoverState(Eigen::Vector3d(0, 0, 1));
  EXPECT_LT((model.ProjectToTaut(h) - h).norm(), 1e-12);
}

TEST(HybridModelTest, ProjectToTautGivesNoImpulseToAnApproachingPayload) {
  const Params p;
  const HybridModel model(p);
  // payload on the cable sphere, moving toward the quadrotor (thrown up along the cable)
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0, 0, 1.2);
  s.p_WL_W = Eigen::Vector3d(0, 0, 1.2 - p.cable_length_m);
  s.v_WQ_W = Eigen::Vector3d(0.1, 0, -0.2);
  s.v_WL_W = Eigen::Vector3d(0.1, 0.2, 1.5);
  const StateVector x = s.ToVector();
  const StateVector y = model.ProjectToTaut(x);
  EXPECT_EQ((y - x).norm(), 0.0) << "a cable cannot push: no velocity change, no move";
  // moving away by a hair: the impulse is the (small) inelastic one, continuous in v_rel
  s.v_WL_W = Eigen::Vector3d(0.1, 0.2, -0.2 - 1e-3);
  const StateVector z = model.ProjectToTaut(s.ToVector());
  using I = StateIndex;
  EXPECT_LT((z.segment<3>(I::kPayloadVel) - s.v_WL_W).norm(), 1e-3);
}

TEST(HybridModelTest, ProjectToTautMovesPositionsOnlyOutsideTheTautBand) {
  const Params p;
  const HybridModel model(p);
  using I = StateIndex;
  const auto length = [](const StateVector& v) {
    return (v.segment<3>(I::kPayloadPos) - v.segment<3>(I::kQuadPos)).norm();
  };
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0, 0, 1.2);
  // inside the band (what the mode detector calls taut): positions untouched
  for (double d : {p.cable_length_m - 0.9 * p.slack_epsilon_m, p.cable_length_m - 0.01}) {
    s.p_WL_W = s.p_WQ_W + Eigen::Vector3d(0.2, 0, -std::sqrt(d * d - 0.04));
    const StateVector y = model.ProjectToTaut(s.ToVector());
    EXPECT_EQ((y.segment<3>(I::kPayloadPos) - s.p_WL_W).norm(), 0.0) << d;
    EXPECT_EQ((y.segment<3>(I::kQuadPos) - s.p_WQ_W).norm(), 0.0) << d;
  }
  // beyond the length (an estimate off the constraint): back to the length, no further
  s.p_WL_W = s.p_WQ_W + Eigen::Vector3d(0, 0, -(p.cable_length_m + 0.03));
  EXPECT_NEAR(length(model.ProjectToTaut(s.ToVector())), p.cable_length_m, 1e-12);
  // the largest move is the distance to the band's edge
  s.p_WL_W = s.p_WQ_W + Eigen::Vector3d(0, 0, -(p.cable_length_m - 0.2));
  const StateVector y = model.ProjectToTaut(s.ToVector());
  EXPECT_NEAR(length(y), p.cable_length_m - p.slack_epsilon_m, 1e-12);
}

TEST(HybridModelTest, ProjectToTautJacobianMatchesFiniteDifferences) {
  const Params p;
  const HybridModel model(p);
  // payload past the length and falling away (the moved, inelastic branch), and one inside the
  // band approaching (the identity branch): the Jacobian of each piece
  SystemState away;
  away.p_WQ_W = Eigen::Vector3d(0, 0, 1.2);
  away.p_WL_W = Eigen::Vector3d(0.1, 0.05, 1.2 - p.cable_length_m - 0.04);
  away.v_WQ_W = Eigen::Vector3d(0.2, 0, 0.1);
  away.v_WL_W = Eigen::Vector3d(0.3, 0.1, -2.0);
  SystemState approaching = away;
  approaching.p_WL_W = Eigen::Vector3d(0.1, 0.05, 1.2 - p.cable_length_m + 0.02);
  approaching.v_WL_W = Eigen::Vector3d(0.3, 0.1, 1.0);
  for (const SystemState& s : {away, approaching}) {
    const StateVector x = s.ToVector();
    StateMatrix jacobian, fd;
    const StateVector y = model.ProjectToTautJacobian(x, &jacobian);
    EXPECT_EQ(y, model.ProjectToTaut(x));
    for (int i = 0; i < kNx; ++i) {
      const double h = 1e-6;
      StateVector xp = x, xm = x;
      xp(i) += h;
      xm(i) -= h;
      fd.col(i) = (model.ProjectToTaut(xp) - model.ProjectToTaut(xm)) / (2 * h);
    }
    const double error = (jacobian - fd).cwiseAbs().maxCoeff();
    std::printf("jump map Jacobian vs central differences: max error %.2e\n", error);
    // central differences on a map of products and one square root: rounding ~1e-16 / 1e-6;
    // measured 2.6e-10 and 8e-11 (the two branches), bound about 10x that
    EXPECT_LT(error, 3e-9);
  }
}

}  // namespace
}  // namespace hpa
