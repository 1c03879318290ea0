// SolveRiccatiBoxQp against Condense + SolveBoxQp: the same box QP solved on its stage-wise form.
//
// Tolerance 1e-9 relative to max(1, largest |du|): both are direct solves of the same strictly
// convex QP reaching the same active set; they differ by the rounding of two factorisations
// (Riccati over 10 stages against a 40 x 40 Cholesky) amplified by the QP's conditioning.

#include "riccati_qp.h"

#include <gtest/gtest.h>

#include <random>

namespace hpa {
namespace {

constexpr double kTolerance = 1e-9;

// Random time-varying LQ-like problem: A near identity, coupled Hxx block, nonzero Hxu.
void RandomProblem(std::mt19937* rng, std::vector<StateMatrix>* a, std::vector<InputMatrix>* b,
                   std::vector<StageQuadratic>* stages) {
  std::normal_distribution<double> normal(0.0, 1.0);
  const int n = 10;
  a->resize(n);
  b->resize(n);
  stages->resize(n + 1);
  const auto random = [&]() { return normal(*rng); };
  for (int k = 0; k < n; ++k) {
    (*a)[k] = StateMatrix::Identity() + 0.05 * StateMatrix::NullaryExpr(random);
    (*b)[k] = 0.3 * InputMatrix::NullaryExpr(random);
  }
  for (int k = 0; k <= n; ++k) {
    StageQuadratic& s = (*stages)[k];
    const Eigen::Matrix<double, 3, kNx> j = Eigen::Matrix<double, 3, kNx>::NullaryExpr(random);
    s.hxx = StateVector::Constant(1.0 + k).asDiagonal();
    s.hxx += j.transpose() * j;
    s.gx = 3.0 * StateVector::NullaryExpr(random);
    if (k < n) {
      s.huu = Eigen::Vector4d(0.5, 1.0, 1.5, 2.0).asDiagonal();
      s.hxu.row(2) = 0.1 * InputVector::NullaryExpr(random).transpose();
      s.gu = 3.0 * InputVector::NullaryExpr(random);
    }
  }
}

TEST(RiccatiQpTest, MatchesCondensingAndDenseBoxQpWithActiveBounds) {
  std::mt19937 rng(11);
  RiccatiWorkspace ws;
  int active_total = 0;
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<StateMatrix> a;
    std::vector<InputMatrix> b;
    std::vector<StageQuadratic> stages;
    RandomProblem(&rng, &a, &b, &stages);
    const int nz = kNu * static_cast<int>(a.size());
    const double shift = trial % 2 == 0 ? 0.0 : 0.7;  // with and without the LM term
    const double width = trial < 10 ? 0.5 : 1e9;      // tight box (active bounds) or none
    const Eigen::VectorXd lb = Eigen::VectorXd::Constant(nz, -width);
    const Eigen::VectorXd ub = Eigen::VectorXd::Constant(nz, 0.8 * width);
    Eigen::MatrixXd h;
    Eigen::VectorXd g;
    Condense(a, b, stages, &h, &g);
    h.diagonal().array() += shift;
    Eigen::VectorXd du_dense = Eigen::VectorXd::Zero(nz), du = Eigen::VectorXd::Zero(nz);
    const BoxQpResult dense = SolveBoxQp(h, g, lb, ub, &du_dense);
    const BoxQpResult riccati = SolveRiccatiBoxQp(a, b, stages, shift, lb, ub, &du, &ws);
    ASSERT_EQ(dense.status, BoxQpStatus::kSolved);
    ASSERT_EQ(riccati.status, BoxQpStatus::kSolved);
    EXPECT_EQ(riccati.active, dense.active) << trial;
    EXPECT_LT((du - du_dense).cwiseAbs().maxCoeff() / std::max(1.0, du_dense.cwiseAbs().maxCoeff()),
              kTolerance)
        << trial;
    Eigen::VectorXd g_stage;
    StageQpGradient(a, b, stages, &g_stage);
    EXPECT_LT((g_stage - g).cwiseAbs().maxCoeff() / std::max(1.0, g.cwiseAbs().maxCoeff()), 1e-12);
    active_total += riccati.active;
  }
  EXPECT_GT(active_total, 0);  // the tight boxes did bind
}

TEST(RiccatiQpTest, ReportsAnIndefiniteInputHessian) {
  std::mt19937 rng(12);
  std::vector<StateMatrix> a;
  std::vector<InputMatrix> b;
  std::vector<StageQuadratic> stages;
  RandomProblem(&rng, &a, &b, &stages);
  stages[3].huu(1, 1) = -50.0;
  RiccatiWorkspace ws;
  Eigen::VectorXd du;
  const Eigen::VectorXd big = Eigen::VectorXd::Constant(kNu * 10, 1e9);
  EXPECT_EQ(SolveRiccatiBoxQp(a, b, stages, 0.0, -big, big, &du, &ws).status,
            BoxQpStatus::kNotPositiveDefinite);
}

}  // namespace
}  // namespace hpa
