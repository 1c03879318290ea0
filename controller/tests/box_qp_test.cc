#include "hpa/controller/box_qp.h"

#include <gtest/gtest.h>

#include <random>

#include "hpa/controller/condensing.h"

namespace hpa {
namespace {

TEST(BoxQpTest, UnconstrainedIsNewtonStep) {
  Eigen::MatrixXd h(2, 2);
  h << 4, 1, 1, 3;
  const Eigen::VectorXd g = Eigen::Vector2d(1, -2);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(2);
  const Eigen::VectorXd big = Eigen::VectorXd::Constant(2, 1e3);
  const BoxQpResult r = SolveBoxQp(h, g, -big, big, &z);
  EXPECT_EQ(r.status, BoxQpStatus::kSolved);
  EXPECT_TRUE(z.isApprox(-h.ldlt().solve(g), 1e-12));
}

TEST(BoxQpTest, KnownAnswerWithActiveBounds) {
  // separable: z_i = clamp(-g_i / h_ii) -> (1, -0.5, -1)
  const Eigen::MatrixXd h = Eigen::Vector3d(1, 2, 1).asDiagonal();
  const Eigen::VectorXd g = Eigen::Vector3d(-2, 1, 5);
  Eigen::VectorXd z = Eigen::Vector3d(0.3, 0.3, 0.3);
  const Eigen::VectorXd lb = Eigen::Vector3d::Constant(-1), ub = Eigen::Vector3d::Constant(1);
  const BoxQpResult r = SolveBoxQp(h, g, lb, ub, &z);
  EXPECT_EQ(r.status, BoxQpStatus::kSolved);
  EXPECT_TRUE(z.isApprox(Eigen::Vector3d(1, -0.5, -1), 1e-14));
  EXPECT_EQ(r.active, 2);
}

TEST(BoxQpTest, RandomProblemsSatisfyKkt) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    const int n = 40;
    Eigen::MatrixXd m(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) m(i, j) = normal(rng);
    const Eigen::MatrixXd h = m.transpose() * m + 0.1 * Eigen::MatrixXd::Identity(n, n);
    Eigen::VectorXd g(n), lb(n), ub(n);
    for (int i = 0; i < n; ++i) {
      g(i) = 10 * normal(rng);
      lb(i) = -std::abs(normal(rng));
      ub(i) = std::abs(normal(rng));
    }
    Eigen::VectorXd z = Eigen::VectorXd::Zero(n);
    const BoxQpResult r = SolveBoxQp(h, g, lb, ub, &z);
    ASSERT_EQ(r.status, BoxQpStatus::kSolved) << "trial " << trial;
    const Eigen::VectorXd grad = h * z + g;
    // KKT for the box: feasibility exact, gradient zero on free variables and pointing out of
    // the box on active ones; 1e-8 relative to |g| ~ 30 covers the Cholesky rounding (~1e-12)
    for (int i = 0; i < n; ++i) {
      ASSERT_GE(z(i), lb(i));
      ASSERT_LE(z(i), ub(i));
      if (z(i) > lb(i) && z(i) < ub(i)) EXPECT_NEAR(grad(i), 0.0, 1e-8);
      if (z(i) == lb(i)) EXPECT_GE(grad(i), -1e-8);
      if (z(i) == ub(i)) EXPECT_LE(grad(i), 1e-8);
    }
  }
}

TEST(BoxQpTest, ReportsIndefiniteHessian) {
  const Eigen::MatrixXd h = Eigen::Vector2d(1, -1).asDiagonal();
  Eigen::VectorXd z = Eigen::VectorXd::Zero(2);
  const BoxQpResult r =
      SolveBoxQp(h, Eigen::Vector2d(0.5, 0.5), Eigen::Vector2d(-1, -1), Eigen::Vector2d(1, 1), &z);
  EXPECT_EQ(r.status, BoxQpStatus::kNotPositiveDefinite);
}

// Known-answer LQ: for x_{k+1} = A x_k + B u_k and cost sum x^T Q x + u^T R u + x_N^T P x_N
// (as 1/2-scaled Gauss-Newton stages), the condensed QP's solution must equal the
// finite-horizon Riccati feedback u_k = -K_k x_k rolled out from x_0.
TEST(CondensingTest, UnconstrainedLqMatchesRiccati) {
  std::mt19937 rng(3);
  std::normal_distribution<double> normal(0.0, 1.0);
  const int n = 10;
  std::vector<StateMatrix> a(n);
  std::vector<InputMatrix> b(n);
  std::vector<StageQuadratic> stages(n + 1);
  const StateMatrix q = StateVector::Constant(2.0).asDiagonal();
  const Eigen::Matrix4d r = Eigen::Vector4d(0.5, 1.0, 1.5, 2.0).asDiagonal();
  const StateMatrix p_terminal = 5.0 * q;
  for (int k = 0; k < n; ++k) {
    StateMatrix noise;
    for (int i = 0; i < kNx; ++i)
      for (int j = 0; j < kNx; ++j) noise(i, j) = 0.05 * normal(rng);
    a[k] = StateMatrix::Identity() + noise;  // time-varying, like a linearised trajectory
    for (int i = 0; i < kNx; ++i)
      for (int j = 0; j < kNu; ++j) b[k](i, j) = 0.3 * normal(rng);
  }
  StateVector x0;
  for (int i = 0; i < kNx; ++i) x0(i) = normal(rng);

  // nominal trajectory u = 0: x_k = A_{k-1} ... A_0 x0; stage gradients Q x_k
  std::vector<StateVector> x_nom(n + 1);
  x_nom[0] = x0;
  for (int k = 0; k < n; ++k) x_nom[k + 1] = a[k] * x_nom[k];
  for (int k = 0; k <= n; ++k) {
    const StateMatrix qk = (k == n) ? p_terminal : q;
    stages[k].hxx = qk;
    stages[k].gx = qk * x_nom[k];
    if (k < n) stages[k].huu = r;
  }
  // dx_0 = 0 in the condensed QP, so the x_0 term only shifts the cost
  Eigen::MatrixXd h;
  Eigen::VectorXd g;
  Condense(a, b, stages, &h, &g);
  Eigen::VectorXd du = Eigen::VectorXd::Zero(kNu * n);
  const Eigen::VectorXd big = Eigen::VectorXd::Constant(kNu * n, 1e9);
  ASSERT_EQ(SolveBoxQp(h, g, -big, big, &du).status, BoxQpStatus::kSolved);

  // Riccati: P_N = P, K_k = (R + B^T P B)^-1 B^T P A, P_k = Q + A^T P (A - B K)
  std::vector<Eigen::Matrix<double, kNu, kNx>> gain(n);
  StateMatrix p = p_terminal;
  for (int k = n - 1; k >= 0; --k) {
    const Eigen::Matrix4d s = r + b[k].transpose() * p * b[k];
    gain[k] = s.ldlt().solve(b[k].transpose() * p * a[k]);
    p = q + a[k].transpose() * p * (a[k] - b[k] * gain[k]);
  }
  StateVector x = x0;
  for (int k = 0; k < n; ++k) {
    const InputVector u = -gain[k] * x;
    // 1e-8 relative: both are direct solves of the same well-conditioned problem; the
    // measured difference is ~1e-12
    EXPECT_TRUE(du.segment<kNu>(kNu * k).isApprox(u, 1e-8)) << "stage " << k;
    x = a[k] * x + b[k] * u;
  }
}

}  // namespace
}  // namespace hpa
