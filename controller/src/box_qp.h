#pragma once
// Private to the controller library (RTI). Dense box-constrained QP, solved in-house with Eigen by
// a primal active-set method:
//   min 1/2 z^T H z + g^T z   s.t.  lb <= z <= ub,   H symmetric positive definite.

#include <Eigen/Core>

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

/// Solves the box QP by a primal active-set method. z holds the start on entry (clamped into
/// the box, so any warm start is fine) and the solution on exit; every iterate is feasible, so
/// on kMaxIterations z is still feasible and no worse than the start. Requires lb <= ub.
/// KKT tolerance: multipliers must be >= -kkt_tolerance * (1 + |g|_inf).
BoxQpResult SolveBoxQp(const Eigen::MatrixXd& h, const Eigen::VectorXd& g,
                       const Eigen::VectorXd& lb, const Eigen::VectorXd& ub, Eigen::VectorXd* z,
                       int max_iterations = 200, double kkt_tolerance = 1e-10);

}  // namespace hpa
