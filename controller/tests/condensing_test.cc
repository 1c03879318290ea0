// Condensing of a linearised OCP onto its inputs (a private header of the controller library:
// tests see src/).

#include "condensing.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <random>

#include "box_qp.h"

namespace hpa {
namespace {

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
