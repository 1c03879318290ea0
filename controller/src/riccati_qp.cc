#include "riccati_qp.h"

#include <Eigen/Cholesky>
#include <algorithm>

namespace hpa {
namespace {

// Gradient of the QP at du = z: forward dx_{k+1} = A dx_k + B z_k, then the adjoint
// lambda_N = Hxx_N dx_N + gx_N, grad_k = (Huu + shift) z_k + Hxu^T dx_k + gu_k + B^T lambda_{k+1},
// lambda_k = Hxx dx_k + Hxu z_k + gx_k + A^T lambda_{k+1}.
void GradientAt(const std::vector<StateMatrix>& a, const std::vector<InputMatrix>& b,
                const std::vector<StageQuadratic>& stages, double shift, const Eigen::VectorXd& z,
                RiccatiWorkspace* ws) {
  const int n = static_cast<int>(a.size());
  ws->dx[0].setZero();
  for (int k = 0; k < n; ++k) {
    ws->dx[k + 1].noalias() = a[k] * ws->dx[k];
    ws->dx[k + 1].noalias() += b[k] * z.segment<kNu>(kNu * k);
  }
  StateVector lambda = stages[n].hxx * ws->dx[n] + stages[n].gx;
  for (int k = n - 1; k >= 0; --k) {
    const StageQuadratic& s = stages[k];
    const InputVector z_k = z.segment<kNu>(kNu * k);
    ws->grad.segment<kNu>(kNu * k) = s.huu * z_k + shift * z_k + s.hxu.transpose() * ws->dx[k] +
                                     s.gu + b[k].transpose() * lambda;
    lambda = s.hxx * ws->dx[k] + s.hxu * z_k + s.gx + a[k].transpose() * lambda;
  }
}

// Values of stage k's inputs fixed by the working set (zero where free) and the free mask.
void FixedInputs(const std::vector<int>& fixed, const Eigen::VectorXd& z, int k, InputVector* c,
                 InputVector* free) {
  for (int i = 0; i < kNu; ++i) {
    const bool is_fixed = fixed[kNu * k + i] != 0;
    (*c)(i) = is_fixed ? z(kNu * k + i) : 0.0;
    (*free)(i) = is_fixed ? 0.0 : 1.0;
  }
}

// Minimiser of the QP with the working set's inputs fixed at z, into ws->target: Riccati
// recursion on du = v + c (v zero on the fixed inputs, c their values), then the forward pass.
// False when a stage's reduced input Hessian is not positive definite.
bool SolveSubproblem(const std::vector<StateMatrix>& a, const std::vector<InputMatrix>& b,
                     const std::vector<StageQuadratic>& stages, double shift,
                     const Eigen::VectorXd& z, RiccatiWorkspace* ws) {
  const int n = static_cast<int>(a.size());
  StateMatrix p = stages[n].hxx;  // value function 1/2 dx^T P dx + p^T dx
  StateVector p_vec = stages[n].gx;
  StateMatrix pa;
  InputVector c, free;
  for (int k = n - 1; k >= 0; --k) {
    const StageQuadratic& s = stages[k];
    FixedInputs(ws->fixed, z, k, &c, &free);
    const InputMatrix b_free = b[k] * free.asDiagonal();
    const StateVector pe = p * (b[k] * c) + p_vec;  // value gradient at the fixed inputs' offset
    pa.noalias() = p.lazyProduct(a[k]);
    Eigen::Matrix4d r = s.huu + shift * Eigen::Matrix4d::Identity();
    const InputVector r_lin = (s.gu + r * c).cwiseProduct(free);
    r = free.asDiagonal() * r * free.asDiagonal();
    r.diagonal() += InputVector::Ones() - free;  // fixed inputs: decoupled, v_i = 0
    r.noalias() += b_free.transpose() * p * b_free;
    Eigen::Matrix<double, kNu, kNx> g_x = (s.hxu * free.asDiagonal()).transpose();
    g_x.noalias() += b_free.transpose() * pa;
    const InputVector g_u = r_lin + b_free.transpose() * pe;
    const Eigen::LLT<Eigen::Matrix4d> llt(r);
    if (llt.info() != Eigen::Success) return false;
    ws->gain[k] = -llt.solve(g_x);
    ws->feedforward[k] = -llt.solve(g_u);
    StateMatrix p_next = s.hxx;
    p_next.noalias() += a[k].transpose() * pa;
    p_next.noalias() += g_x.transpose() * ws->gain[k];
    p = 0.5 * (p_next + p_next.transpose());
    p_vec = s.gx + s.hxu * c + a[k].transpose() * pe + g_x.transpose() * ws->feedforward[k];
  }
  ws->dx[0].setZero();
  for (int k = 0; k < n; ++k) {
    FixedInputs(ws->fixed, z, k, &c, &free);
    const InputVector du = ws->gain[k] * ws->dx[k] + ws->feedforward[k] + c;
    ws->target.segment<kNu>(kNu * k) = du;
    ws->dx[k + 1].noalias() = a[k] * ws->dx[k];
    ws->dx[k + 1].noalias() += b[k] * du;
  }
  return true;
}

// Moves z toward ws->target as far as the box allows (free inputs only); true when a free input
// reached a bound (it joins the working set).
bool StepToTarget(const Eigen::VectorXd& lb, const Eigen::VectorXd& ub, Eigen::VectorXd* z,
                  RiccatiWorkspace* ws) {
  const int n = static_cast<int>(z->size());
  double alpha = 1.0;
  int blocking = -1;
  for (int i = 0; i < n; ++i) {
    if (ws->fixed[i] != 0) continue;
    const double p = ws->target(i) - (*z)(i);
    const double t = p < 0.0 ? (lb(i) - (*z)(i)) / p : p > 0.0 ? (ub(i) - (*z)(i)) / p : alpha;
    if (t < alpha) alpha = t, blocking = i;
  }
  alpha = std::max(alpha, 0.0);
  for (int i = 0; i < n; ++i) {
    if (ws->fixed[i] == 0) (*z)(i) += alpha * (ws->target(i) - (*z)(i));
  }
  if (blocking < 0) return false;
  const bool lower = ((*z)(blocking)-lb(blocking)) <= (ub(blocking) - (*z)(blocking));
  (*z)(blocking) = lower ? lb(blocking) : ub(blocking);
  ws->fixed[blocking] = lower ? -1 : +1;
  return true;
}

}  // namespace

void StageQpGradient(const std::vector<StateMatrix>& a, const std::vector<InputMatrix>& b,
                     const std::vector<StageQuadratic>& stages, Eigen::VectorXd* g) {
  const int n = static_cast<int>(a.size());
  g->resize(kNu * n);
  StateVector lambda = stages[n].gx;
  for (int k = n - 1; k >= 0; --k) {
    g->segment<kNu>(kNu * k).noalias() = stages[k].gu + b[k].transpose() * lambda;
    lambda = stages[k].gx + a[k].transpose() * lambda;
  }
}

BoxQpResult SolveRiccatiBoxQp(const std::vector<StateMatrix>& a, const std::vector<InputMatrix>& b,
                              const std::vector<StageQuadratic>& stages, double huu_shift,
                              const Eigen::VectorXd& lb, const Eigen::VectorXd& ub,
                              Eigen::VectorXd* du, RiccatiWorkspace* ws, int max_iterations,
                              double kkt_tolerance) {
  BoxQpResult result;
  const int n = static_cast<int>(a.size());
  const int nz = kNu * n;
  ws->gain.resize(n);
  ws->feedforward.resize(n);
  ws->dx.resize(n + 1);
  ws->grad.resize(nz);
  ws->target.resize(nz);
  if (!lb.allFinite() || !ub.allFinite()) {
    result.status = BoxQpStatus::kNonFinite;
    return result;
  }
  if (du->size() != nz || !du->allFinite()) du->setZero(nz);
  *du = du->cwiseMax(lb).cwiseMin(ub);
  ws->fixed.assign(nz, 0);
  for (int i = 0; i < nz; ++i) {
    if ((*du)(i) <= lb(i) || lb(i) == ub(i)) ws->fixed[i] = -1;
    if ((*du)(i) >= ub(i) && lb(i) != ub(i)) ws->fixed[i] = +1;
  }
  StageQpGradient(a, b, stages, &ws->grad);
  if (!ws->grad.allFinite()) {
    result.status = BoxQpStatus::kNonFinite;
    return result;
  }
  const double mult_tol = kkt_tolerance * (1.0 + ws->grad.lpNorm<Eigen::Infinity>());
  for (int iter = 0; iter < max_iterations; ++iter) {
    result.iterations = iter + 1;
    if (!SolveSubproblem(a, b, stages, huu_shift, *du, ws)) {
      result.status = BoxQpStatus::kNotPositiveDefinite;
      return result;
    }
    if (StepToTarget(lb, ub, du, ws)) continue;
    // at the subproblem's minimiser: release the bound with the worst multiplier, if any
    GradientAt(a, b, stages, huu_shift, *du, ws);
    int release = -1;
    double worst = -mult_tol;
    for (int i = 0; i < nz; ++i) {
      if (ws->fixed[i] == 0 || lb(i) == ub(i)) continue;
      const double multiplier = ws->fixed[i] < 0 ? ws->grad(i) : -ws->grad(i);
      if (multiplier < worst) worst = multiplier, release = i;
    }
    if (release < 0) {
      result.status = BoxQpStatus::kSolved;
      result.active = static_cast<int>(nz - std::count(ws->fixed.begin(), ws->fixed.end(), 0));
      return result;
    }
    ws->fixed[release] = 0;
  }
  result.status = BoxQpStatus::kMaxIterations;
  result.active = static_cast<int>(nz - std::count(ws->fixed.begin(), ws->fixed.end(), 0));
  return result;
}

}  // namespace hpa
