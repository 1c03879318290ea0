#include "box_qp.h"

#include <Eigen/Cholesky>
#include <algorithm>

namespace hpa {
namespace {

// Working set from the (clamped) start: -1 at the lower bound, +1 at the upper, 0 free.
void InitialWorkingSet(const Eigen::VectorXd& z, const Eigen::VectorXd& lb,
                       const Eigen::VectorXd& ub, std::vector<int>* fixed) {
  const int n = static_cast<int>(z.size());
  fixed->assign(n, 0);
  for (int i = 0; i < n; ++i) {
    if (z(i) <= lb(i)) (*fixed)[i] = -1;
    if (z(i) >= ub(i)) (*fixed)[i] = +1;
    if (lb(i) == ub(i)) (*fixed)[i] = -1;
  }
}

// Bounds active in the working set.
int CountActive(const std::vector<int>& fixed) {
  return static_cast<int>(std::count_if(fixed.begin(), fixed.end(), [](int f) { return f != 0; }));
}

// Newton step of the equality-constrained subproblem on the free variables,
// H_FF p = -(H z + g)_F, taken as far as the box allows. Returns false if H_FF is not positive
// definite; *blocked says whether a free variable reached a bound (it joins the working set).
bool FreeStep(const Eigen::MatrixXd& h, const Eigen::VectorXd& g, const Eigen::VectorXd& lb,
              const Eigen::VectorXd& ub, Eigen::VectorXd* z, BoxQpWorkspace* ws, bool* blocked) {
  const std::vector<int>& free_idx = ws->free_idx;
  const int nf = static_cast<int>(free_idx.size());
  *blocked = false;
  if (nf == 0) return true;
  ws->grad.noalias() = h * (*z);
  ws->grad += g;
  auto h_ff = ws->h_ff.topLeftCorner(nf, nf);
  auto p = ws->p.head(nf);
  for (int a = 0; a < nf; ++a) {
    p(a) = -ws->grad(free_idx[a]);
    for (int b = 0; b < nf; ++b) h_ff(a, b) = h(free_idx[a], free_idx[b]);
  }
  Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(h_ff);  // in place: no allocation
  if (llt.info() != Eigen::Success) return false;
  llt.solveInPlace(p);
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
    const int i = blocking;
    const bool lower = ((*z)(i)-lb(i)) <= (ub(i) - (*z)(i));
    (*z)(i) = lower ? lb(i) : ub(i);
    ws->fixed[i] = lower ? -1 : +1;
    *blocked = true;
  }
  return true;
}

// The fixed bound with the most negative multiplier below -mult_tol, or -1 (KKT point).
int WorstMultiplier(const Eigen::MatrixXd& h, const Eigen::VectorXd& g, const Eigen::VectorXd& lb,
                    const Eigen::VectorXd& ub, const Eigen::VectorXd& z, double mult_tol,
                    BoxQpWorkspace* ws) {
  ws->grad.noalias() = h * z;
  ws->grad += g;
  int release = -1;
  double worst = -mult_tol;
  for (int i = 0; i < static_cast<int>(z.size()); ++i) {
    if (ws->fixed[i] == 0 || lb(i) == ub(i)) continue;
    // at lower bound the multiplier is grad_i (>= 0), at upper bound -grad_i (>= 0)
    const double multiplier = (ws->fixed[i] < 0) ? ws->grad(i) : -ws->grad(i);
    if (multiplier < worst) worst = multiplier, release = i;
  }
  return release;
}

}  // namespace

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
  BoxQpWorkspace workspace;
  return SolveBoxQp(h, g, lb, ub, z, &workspace, max_iterations, kkt_tolerance);
}

BoxQpResult SolveBoxQp(const Eigen::MatrixXd& h, const Eigen::VectorXd& g,
                       const Eigen::VectorXd& lb, const Eigen::VectorXd& ub, Eigen::VectorXd* z,
                       BoxQpWorkspace* ws, int max_iterations, double kkt_tolerance) {
  BoxQpResult result;
  const int n = static_cast<int>(g.size());
  if (!h.allFinite() || !g.allFinite() || !lb.allFinite() || !ub.allFinite()) {
    result.status = BoxQpStatus::kNonFinite;
    return result;
  }
  if (z->size() != n || !z->allFinite()) z->setZero(n);
  *z = z->cwiseMax(lb).cwiseMin(ub);
  if (ws->h_ff.rows() != n) ws->h_ff.resize(n, n);
  ws->grad.resize(n);
  ws->p.resize(n);
  ws->free_idx.reserve(n);
  InitialWorkingSet(*z, lb, ub, &ws->fixed);
  const double mult_tol = kkt_tolerance * (1.0 + g.lpNorm<Eigen::Infinity>());
  for (int iter = 0; iter < max_iterations; ++iter) {
    result.iterations = iter + 1;
    ws->free_idx.clear();
    for (int i = 0; i < n; ++i) {
      if (ws->fixed[i] == 0) ws->free_idx.push_back(i);
    }
    bool blocked = false;
    if (!FreeStep(h, g, lb, ub, z, ws, &blocked)) {
      result.status = BoxQpStatus::kNotPositiveDefinite;
      return result;
    }
    if (blocked) continue;
    // at the subproblem's minimiser: release the bound with the worst multiplier, if any
    const int release = WorstMultiplier(h, g, lb, ub, *z, mult_tol, ws);
    if (release < 0) {
      result.status = BoxQpStatus::kSolved;
      result.active = CountActive(ws->fixed);
      return result;
    }
    ws->fixed[release] = 0;
  }
  result.status = BoxQpStatus::kMaxIterations;
  result.active = CountActive(ws->fixed);
  return result;
}

}  // namespace hpa
