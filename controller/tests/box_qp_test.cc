// The in-house box QP (a private header of the controller library: tests see src/).

#include "box_qp.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <random>

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
      if (z(i) > lb(i) && z(i) < ub(i)) {
        EXPECT_NEAR(grad(i), 0.0, 1e-8);
      }
      if (z(i) == lb(i)) {
        EXPECT_GE(grad(i), -1e-8);
      }
      if (z(i) == ub(i)) {
        EXPECT_LE(grad(i), 1e-8);
      }
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

}  // namespace
}  // namespace hpa
