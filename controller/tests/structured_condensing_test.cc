// CondenseStructured (and the sparse Gauss-Newton stage model) against the dense Condense: the
// same QP up to rounding, on random dense problems, on problems with the rigid body's pattern and
// a coupled Hxx / nonzero Hxu, and on an OCP's own linearisation.
//
// Tolerance 1e-12 relative to the largest |entry|: both sum the same products in a different
// order (and skip exact zeros), so they differ by rounding: a few ulps per product accumulated
// over at most 10 stages.

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "closed_loop_sim.h"
#include "condensing.h"
#include "hpa/controller/hpa_mpc.h"
#include "hpa/controller/ocp.h"

namespace hpa {
namespace {

constexpr double kTolerance = 1e-12;

template <typename A, typename B>
double RelativeError(const A& actual, const B& expected) {
  return (actual - expected).cwiseAbs().maxCoeff() / std::max(1.0, expected.cwiseAbs().maxCoeff());
}

// Random problem; `rigid_body`: A with the attitude-decoupled zero blocks, and stage Hessians
// with a coupled block in Hxx and a nonzero Hxu.
void RandomProblem(bool rigid_body, std::mt19937* rng, std::vector<StateMatrix>* a,
                   std::vector<InputMatrix>* b, std::vector<StageQuadratic>* stages) {
  std::normal_distribution<double> normal(0.0, 1.0);
  const int n = kOcpHorizonSteps;
  a->resize(n);
  b->resize(n);
  stages->resize(n + 1);
  for (int k = 0; k < n; ++k) {
    (*a)[k] =
        StateMatrix::Identity() + 0.1 * StateMatrix::NullaryExpr([&]() { return normal(*rng); });
    (*b)[k] = 0.3 * InputMatrix::NullaryExpr([&]() { return normal(*rng); });
    if (rigid_body) {
      (*a)[k].block<7, 12>(12, 0).setZero();
      (*a)[k].block<3, 4>(16, 12).setZero();
    }
  }
  for (int k = 0; k <= n; ++k) {
    StageQuadratic& s = (*stages)[k];
    s.hxx = StateVector::Constant(2.0 + k).asDiagonal();
    s.gx = StateVector::NullaryExpr([&]() { return normal(*rng); });
    if (k < n) {
      s.huu = Eigen::Vector4d(0.5, 1.0, 1.5, 2.0).asDiagonal();
      s.gu = InputVector::NullaryExpr([&]() { return normal(*rng); });
    }
    if (rigid_body) {
      const Eigen::Matrix<double, 2, 6> j =
          Eigen::Matrix<double, 2, 6>::NullaryExpr([&]() { return normal(*rng); });
      s.hxx.block<6, 6>(0, 0) += j.transpose() * j;
      if (k < n) s.hxu(3, 1) = 0.2;
    }
  }
}

TEST(StructuredCondensingTest, MatchesDenseCondensing) {
  std::mt19937 rng(7);
  CondensingWorkspace ws;  // reused across problems of both kinds
  for (bool rigid_body : {false, true}) {
    for (int trial = 0; trial < 5; ++trial) {
      std::vector<StateMatrix> a;
      std::vector<InputMatrix> b;
      std::vector<StageQuadratic> stages;
      RandomProblem(rigid_body, &rng, &a, &b, &stages);
      Eigen::MatrixXd h_dense, h;
      Eigen::VectorXd g_dense, g;
      Condense(a, b, stages, &h_dense, &g_dense);
      CondenseStructured(a, b, stages, &ws, &h, &g);
      EXPECT_LT(RelativeError(h, h_dense), kTolerance) << rigid_body << " " << trial;
      EXPECT_LT(RelativeError(g, g_dense), kTolerance) << rigid_body << " " << trial;
      EXPECT_EQ(ws.attitude_decoupled[0] != 0, rigid_body);
    }
  }
}

// On the OCP's own linearisation (taut and slack, L_cam on): the sparse Gauss-Newton stages
// equal J^T J, J^T r, and the structured condensing equals the dense one.
TEST(StructuredCondensingTest, MatchesDenseOnTheOcpLinearisation) {
  const Params params;
  const auto ref = MakeLissajousReference(params, LissajousSpec());
  for (CableMode mode : {CableMode::kTaut, CableMode::kSlack}) {
    const Ocp ocp = BuildOcp(params, *ref, 1.3, mode, 2.0);
    StateVector x0 = HybridModel(params).HoverState(ref->At(1.3).p_WQ_W);
    x0(StateIndex::kQuadVel) = 0.4;
    x0(StateIndex::kBodyRate + 1) = 0.3;
    const std::vector<InputVector> u(ocp.horizon_steps, InputVector(610.0, 590.0, 605.0, 600.0));
    const OcpLinearization lin = LinearizeAlong(ocp, x0, u);
    std::vector<StageQuadratic> stages(ocp.horizon_steps + 1);
    for (int k = 0; k <= ocp.horizon_steps; ++k) {
      stages[k] = GaussNewtonStage(lin.r[k], lin.r_x[k], lin.r_u[k]);
      Eigen::Matrix<double, kNr, kNx + kNu> j;
      j << lin.r_x[k], lin.r_u[k];
      const Eigen::Matrix<double, kNx + kNu, kNx + kNu> h = j.transpose() * j;
      EXPECT_LT(RelativeError(stages[k].hxx, h.topLeftCorner<kNx, kNx>()), kTolerance);
      EXPECT_LT(RelativeError(stages[k].hxu, h.topRightCorner<kNx, kNu>()), kTolerance);
      EXPECT_LT(RelativeError(stages[k].huu, h.bottomRightCorner<kNu, kNu>()), kTolerance);
      EXPECT_LT(RelativeError(stages[k].gx, lin.r_x[k].transpose() * lin.r[k]), kTolerance);
      EXPECT_LT(RelativeError(stages[k].gu, lin.r_u[k].transpose() * lin.r[k]), kTolerance);
    }
    Eigen::MatrixXd h_dense, h;
    Eigen::VectorXd g_dense, g;
    CondensingWorkspace ws;
    Condense(lin.a, lin.b, stages, &h_dense, &g_dense);
    CondenseStructured(lin.a, lin.b, stages, &ws, &h, &g);
    EXPECT_LT(RelativeError(h, h_dense), kTolerance) << ToString(mode);
    EXPECT_LT(RelativeError(g, g_dense), kTolerance) << ToString(mode);
    EXPECT_TRUE(ws.attitude_decoupled[0]) << ToString(mode);
  }
}

// The terms' declared columns (OcpResidualColumns) hold every nonzero of the stage Jacobians, in
// taut and slack stages, with L_cam on, off and at the state's attitude, at stage 0 and the
// terminal stage; and the Gauss-Newton stage from them is bit-identical to the full scan.
TEST(StructuredCondensingTest, DeclaredColumnsHoldTheJacobians) {
  const Params params;
  const auto ref = MakeLissajousReference(params, LissajousSpec());
  for (CableMode mode : {CableMode::kTaut, CableMode::kSlack}) {
    for (double perception : {0.0, 2.0}) {
      for (bool at_reference : {true, false}) {
        OcpWeights weights = OcpWeights::Tuned();
        weights.cam_at_reference_attitude = at_reference;
        weights.tilt_max_rad = 0.01;  // the soft limits active
        weights.body_rate_max_radps = 0.1;
        const Ocp ocp = BuildOcp(params, *ref, 1.3, mode, perception, weights);
        StateVector x0 = HybridModel(params).HoverState(ref->At(1.3).p_WQ_W);
        x0(StateIndex::kQuadVel) = 0.4;
        x0(StateIndex::kQuat + 1) = 0.1;
        x0(StateIndex::kBodyRate + 1) = 0.3;
        x0.segment<4>(StateIndex::kQuat).normalize();
        const std::vector<InputVector> u(ocp.horizon_steps,
                                         InputVector(610.0, 590.0, 605.0, 600.0));
        const OcpLinearization lin = LinearizeAlong(ocp, x0, u);
        for (int k = 0; k <= ocp.horizon_steps; ++k) {
          for (int i = 0; i < kNr; ++i) {
            for (int c = 0; c < kNx + kNu; ++c) {
              const double v = c < kNx ? lin.r_x[k](i, c) : lin.r_u[k](i, c - kNx);
              if (v != 0.0) {
                EXPECT_TRUE(OcpResidualColumns()[i] >> c & 1u)
                    << ToString(mode) << " row " << i << " column " << c;
              }
            }
          }
          const StageQuadratic full = GaussNewtonStage(lin.r[k], lin.r_x[k], lin.r_u[k]);
          StageQuadratic declared;
          GaussNewtonStage(lin.r[k], lin.r_x[k], lin.r_u[k], OcpResidualColumns(), &declared);
          EXPECT_EQ(declared.hxx, full.hxx);
          EXPECT_EQ(declared.hxu, full.hxu);
          EXPECT_EQ(declared.huu, full.huu);
          EXPECT_EQ(declared.gx, full.gx);
          EXPECT_EQ(declared.gu, full.gu);
        }
      }
    }
  }
}

// The closed loop with every QP method: 3 s of the paper's Lissajous from hover on the analytic
// plant. Same QP up to rounding, and a contracting tracking loop: the flown states agree to 1e-9
// in every component (m, m/s, rad/s), far below the golden runs' tolerances.
TEST(StructuredCondensingTest, ClosedLoopMatchesDenseCondensing) {
  const Params params;
  const auto ref = MakeLissajousReference(params, LissajousSpec());
  std::vector<testing_util::ClosedLoopLog> logs;
  for (RtiQpMethod method :
       {RtiQpMethod::kDenseCondensing, RtiQpMethod::kStructuredCondensing, RtiQpMethod::kRiccati}) {
    MpcSettings settings;
    settings.solvers.rti.qp_method = method;
    HpaMpc mpc(params, ref, settings);
    testing_util::HybridPlant plant(params, HybridModel(params).HoverState(ref->At(0).p_WQ_W),
                                    CableMode::kTaut);
    logs.push_back(testing_util::RunClosedLoop(params, &mpc, &plant, 3.0));
  }
  for (size_t m = 1; m < logs.size(); ++m) {
    ASSERT_EQ(logs[0].states.size(), logs[m].states.size());
    double max_diff = 0.0;
    for (size_t i = 0; i < logs[0].states.size(); ++i) {
      const StateVector d = logs[0].states[i].ToVector() - logs[m].states[i].ToVector();
      max_diff = std::max(max_diff, d.cwiseAbs().maxCoeff());
    }
    EXPECT_LT(max_diff, 1e-9) << "qp method " << m;
    std::printf("closed loop, qp method %zu against dense condensing: max state difference %.3g\n",
                m, max_diff);
  }
}

// A scenario's controller.qp_method names one of the three, and anything else is refused with
// the key and the known names.
TEST(StructuredCondensingTest, QpMethodNamesParseAndUnknownOnesAreRefused) {
  EXPECT_EQ(ParseRtiQpMethod("dense"), RtiQpMethod::kDenseCondensing);
  EXPECT_EQ(ParseRtiQpMethod("structured"), RtiQpMethod::kStructuredCondensing);
  EXPECT_EQ(ParseRtiQpMethod("riccati"), RtiQpMethod::kRiccati);
  EXPECT_EQ(RtiQpMethodNames().size(), 3u);
  for (const std::string& name : RtiQpMethodNames()) EXPECT_NO_THROW(ParseRtiQpMethod(name));
  ControllerConfig config;
  config.settings["qp_method"] = std::string("hpipm");
  const Params params;
  try {
    MakeController(config, params, MakeLissajousReference(params, LissajousSpec()));
    FAIL() << "qp_method hpipm was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("controller.qp_method"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("riccati"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hpa
