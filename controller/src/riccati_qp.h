#pragma once
// Private to the controller library (RTI). The RTI's box-constrained QP solved on its stage-wise
// form, without condensing:
//   min sum_k 1/2 [dx;du]^T [Hxx Hxu; Hxu^T Huu + shift I] [dx;du] + gx^T dx + gu^T du
//       (+ terminal 1/2 dx_N^T Hxx_N dx_N + gx_N^T dx_N)
//   s.t. dx_{k+1} = A_k dx_k + B_k du_k, dx_0 = 0,  lb <= du <= ub.
// A primal active-set method with the same working-set rules as SolveBoxQp, each equality-
// constrained subproblem (inputs in the working set fixed at their bounds) solved by a Riccati
// recursion over the stages, and the bound multipliers by the adjoint. Same solution as Condense +
// SolveBoxQp up to rounding; O(N nx^3) per working-set change instead of the O(N^2 nx^2 nu)
// condensing plus a dense QP.

#include <Eigen/Core>
#include <vector>

#include "box_qp.h"
#include "condensing.h"

namespace hpa {

/// Scratch of SolveRiccatiBoxQp, kept between calls (no allocation once sized).
struct RiccatiWorkspace {
  std::vector<Eigen::Matrix<double, kNu, kNx>> gain;  // feedback K_k  (N)
  std::vector<InputVector> feedforward;               // k_k  (N)
  std::vector<StateVector> dx;                        // state deviations  (N + 1)
  std::vector<int> fixed;  // working set: -1 lower, +1 upper, 0 free  (4N)
  Eigen::VectorXd grad;    // gradient of the QP at the iterate  (4N)
  Eigen::VectorXd target;  // subproblem minimiser  (4N)
};

/// The QP's gradient at du = 0 (what Condense returns as g), by the adjoint.
void StageQpGradient(const std::vector<StateMatrix>& a, const std::vector<InputMatrix>& b,
                     const std::vector<StageQuadratic>& stages, Eigen::VectorXd* g);

/// Solves the stage-wise box QP above. du holds the start on entry (clamped into the box) and the
/// solution on exit; statuses as SolveBoxQp (kNotPositiveDefinite: a stage's reduced input
/// Hessian is not positive definite, i.e. the condensed one is not).
BoxQpResult SolveRiccatiBoxQp(const std::vector<StateMatrix>& a, const std::vector<InputMatrix>& b,
                              const std::vector<StageQuadratic>& stages, double huu_shift,
                              const Eigen::VectorXd& lb, const Eigen::VectorXd& ub,
                              Eigen::VectorXd* du, RiccatiWorkspace* workspace,
                              int max_iterations = 200, double kkt_tolerance = 1e-10);

}  // namespace hpa
