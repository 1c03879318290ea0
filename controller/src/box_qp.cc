#include "box_qp.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <vector>

namespace hpa {

const char* ToString(BoxQpStatus status) {
  switch (status) {
    case BoxQpStatus::kSolved:
      return "solved";
    case BoxQpStatus::kMaxIterations:
      return "max_iterations";
    case BoxQpStatus::kNotPositiveDefinite:
      return "not_positive_definite";
    case BoxQpStatus::kNonFinite:
      return "non_finite";
  }
  return "unknown";
}

BoxQpResult SolveBoxQp(const Eigen::MatrixXd& h, const Eigen::VectorXd& g,
                       const Eigen::VectorXd& lb, const Eigen::VectorXd& ub, Eigen::VectorXd* z,
                       int max_iterations, double kkt_tolerance) {
  BoxQpResult result;
  const int n = static_cast<int>(g.size());
  if (!h.allFinite() || !g.allFinite() || !lb.allFinite() || !ub.allFinite()) {
    result.status = BoxQpStatus::kNonFinite;
    return result;
  }
  if (z->size() != n || !z->allFinite()) *z = Eigen::VectorXd::Zero(n);
  *z = z->cwiseMax(lb).cwiseMin(ub);

  // working set: -1 fixed at lower bound, +1 fixed at upper bound, 0 free
  std::vector<int> fixed(n, 0);
  for (int i = 0; i < n; ++i) {
    if ((*z)(i) <= lb(i)) fixed[i] = -1;
    if ((*z)(i) >= ub(i)) fixed[i] = +1;
    if (lb(i) == ub(i)) fixed[i] = -1;
  }
  const double mult_tol = kkt_tolerance * (1.0 + g.lpNorm<Eigen::Infinity>());

  std::vector<int> free_idx;
  free_idx.reserve(n);
  Eigen::MatrixXd h_ff;
  Eigen::VectorXd rhs, z_free;
  Eigen::LLT<Eigen::MatrixXd> llt;
  for (int iter = 0; iter < max_iterations; ++iter) {
    result.iterations = iter + 1;
    // equality-constrained subproblem on the free variables: H_FF z_F = -(g_F + H_FA z_A)
    free_idx.clear();
    for (int i = 0; i < n; ++i) {
      if (fixed[i] == 0) free_idx.push_back(i);
    }
    const int nf = static_cast<int>(free_idx.size());
    bool moved_to_bound = false;
    if (nf > 0) {
      const Eigen::VectorXd grad = h * (*z) + g;  // full gradient at the current point
      h_ff.resize(nf, nf);
      rhs.resize(nf);
      for (int a = 0; a < nf; ++a) {
        rhs(a) = -grad(free_idx[a]);
        for (int b = 0; b < nf; ++b) h_ff(a, b) = h(free_idx[a], free_idx[b]);
      }
      llt.compute(h_ff);
      if (llt.info() != Eigen::Success) {
        result.status = BoxQpStatus::kNotPositiveDefinite;
        return result;
      }
      // Newton step p on the free variables (fixed ones do not move)
      const Eigen::VectorXd p = llt.solve(rhs);
      // longest feasible step along p, up to 1
      double alpha = 1.0;
      int blocking = -1;
      for (int a = 0; a < nf; ++a) {
        const int i = free_idx[a];
        if (p(a) < 0.0) {
          const double t = (lb(i) - (*z)(i)) / p(a);
          if (t < alpha) alpha = t, blocking = i;
        } else if (p(a) > 0.0) {
          const double t = (ub(i) - (*z)(i)) / p(a);
          if (t < alpha) alpha = t, blocking = i;
        }
      }
      alpha = std::max(alpha, 0.0);
      for (int a = 0; a < nf; ++a) (*z)(free_idx[a]) += alpha * p(a);
      if (blocking >= 0) {
        // the blocking variable joins the working set at its bound
        const int i = blocking;
        const bool lower = ((*z)(i)-lb(i)) <= (ub(i) - (*z)(i));
        (*z)(i) = lower ? lb(i) : ub(i);
        fixed[i] = lower ? -1 : +1;
        moved_to_bound = true;
      }
    }
    if (moved_to_bound) continue;

    // at the subproblem's minimiser: check the multipliers of the fixed bounds
    const Eigen::VectorXd grad = h * (*z) + g;
    int release = -1;
    double worst = -mult_tol;
    for (int i = 0; i < n; ++i) {
      if (fixed[i] == 0 || lb(i) == ub(i)) continue;
      // at lower bound the multiplier is grad_i (>= 0), at upper bound -grad_i (>= 0)
      const double multiplier = (fixed[i] < 0) ? grad(i) : -grad(i);
      if (multiplier < worst) worst = multiplier, release = i;
    }
    if (release < 0) {
      result.status = BoxQpStatus::kSolved;
      result.active =
          static_cast<int>(std::count_if(fixed.begin(), fixed.end(), [](int f) { return f != 0; }));
      return result;
    }
    fixed[release] = 0;
  }
  result.status = BoxQpStatus::kMaxIterations;
  result.active =
      static_cast<int>(std::count_if(fixed.begin(), fixed.end(), [](int f) { return f != 0; }));
  return result;
}

}  // namespace hpa
