#pragma once
// Private to the controller library (RTI). Dense box-constrained QP, solved in-house with Eigen by
// a primal active-set method:
//   min 1/2 z^T H z + g^T z   s.t.  lb <= z <= ub,   H symmetric positive definite.

#include <Eigen/Core>
#include <vector>

namespace hpa {

/// Outcome of a box-QP solve.
enum class BoxQpStatus { kSolved, kMaxIterations, kNotPositiveDefinite, kNonFinite };

/// Name of a box-QP status for logs.
const char* ToString(BoxQpStatus status);

/// Result of SolveBoxQp.
struct BoxQpResult {
  BoxQpStatus status = BoxQpStatus::kSolved;
  int iterations = 0;  // active-set changes (each one Cholesky of the free block)
  int active = 0;      // bounds active at the returned point
};

/// Scratch of SolveBoxQp, kept between calls: after the first solve of a size, none allocates.
struct BoxQpWorkspace {
  std::vector<int> fixed;     // working set: -1 at lower bound, +1 at upper bound, 0 free  (n)
  std::vector<int> free_idx;  // indices of the free variables
  Eigen::MatrixXd h_ff;       // Hessian of the free variables (top-left block used)  (n x n)
  Eigen::VectorXd grad;       // H z + g  (n)
  Eigen::VectorXd p;          // Newton step on the free variables (head used)  (n)
};

/// Solves the box QP by a primal active-set method. z holds the start on entry (clamped into
/// the box, so any warm start is fine) and the solution on exit; every iterate is feasible, so
/// on kMaxIterations z is still feasible and no worse than the start. Requires lb <= ub.
/// KKT tolerance: multipliers must be >= -kkt_tolerance * (1 + |g|_inf).
BoxQpResult SolveBoxQp(const Eigen::MatrixXd& h, const Eigen::VectorXd& g,
                       const Eigen::VectorXd& lb, const Eigen::VectorXd& ub, Eigen::VectorXd* z,
                       int max_iterations = 200, double kkt_tolerance = 1e-10);

/// SolveBoxQp with its scratch in `workspace` (no heap allocation once sized).
BoxQpResult SolveBoxQp(const Eigen::MatrixXd& h, const Eigen::VectorXd& g,
                       const Eigen::VectorXd& lb, const Eigen::VectorXd& ub, Eigen::VectorXd* z,
                       BoxQpWorkspace* workspace, int max_iterations = 200,
                       double kkt_tolerance = 1e-10);

}  // namespace hpa
