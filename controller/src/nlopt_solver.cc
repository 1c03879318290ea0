#include "hpa/controller/nlopt_solver.h"

#include <nlopt.h>

#include <algorithm>
#include <cmath>

#include "hpa/controller/ocp_solver.h"

namespace hpa {
namespace {

// Data the NLopt callback needs; decision variables are u / u_hover.
struct Problem {
  const Ocp* ocp = nullptr;
  const StateVector* x0 = nullptr;
  int evaluations = 0;
  std::vector<InputVector> u;
  Eigen::VectorXd gradient;
};

double Objective(unsigned n, const double* z, double* grad, void* data) {
  auto* p = static_cast<Problem*>(data);
  ++p->evaluations;
  const double scale = p->ocp->u_hover_radps;
  for (int k = 0; k < p->ocp->horizon_steps; ++k) {
    for (int i = 0; i < kNu; ++i) p->u[k](i) = z[kNu * k + i] * scale;
  }
  if (grad == nullptr) return OcpCost(*p->ocp, *p->x0, p->u);
  const double cost = OcpCostAndGradient(*p->ocp, *p->x0, p->u, &p->gradient);
  for (unsigned i = 0; i < n; ++i) grad[i] = p->gradient(i) * scale;
  return cost;
}

}  // namespace

NloptResult NloptSolve(const Ocp& ocp, const StateVector& x0,
                       const std::vector<InputVector>& u_guess, const NloptSettings& settings) {
  const int n = ocp.horizon_steps;
  const unsigned dim = static_cast<unsigned>(kNu * n);
  const double scale = ocp.u_hover_radps;
  std::vector<double> z(dim), lb(dim), ub(dim);
  for (int k = 0; k < n; ++k) {
    for (int i = 0; i < kNu; ++i) {
      lb[kNu * k + i] = ocp.u_min_radps(i) / scale;
      ub[kNu * k + i] = ocp.u_max_radps(i) / scale;
      z[kNu * k + i] = std::clamp(u_guess[k](i) / scale, lb[kNu * k + i], ub[kNu * k + i]);
    }
  }
  Problem problem;
  problem.ocp = &ocp;
  problem.x0 = &x0;
  problem.u.resize(n);

  nlopt_opt opt = nlopt_create(NLOPT_LD_LBFGS, dim);
  nlopt_set_lower_bounds(opt, lb.data());
  nlopt_set_upper_bounds(opt, ub.data());
  nlopt_set_min_objective(opt, Objective, &problem);
  nlopt_set_ftol_rel(opt, settings.ftol_rel);
  nlopt_set_xtol_rel(opt, settings.xtol_rel);
  nlopt_set_maxeval(opt, settings.max_evaluations);
  nlopt_set_maxtime(opt, settings.max_time_s);
  double cost = 0.0;
  const nlopt_result code = nlopt_optimize(opt, z.data(), &cost);
  nlopt_destroy(opt);

  NloptResult result;
  result.nlopt_code = static_cast<int>(code);
  result.evaluations = problem.evaluations;
  result.u.resize(n);
  for (int k = 0; k < n; ++k) {
    for (int i = 0; i < kNu; ++i) {
      result.u[k](i) = std::clamp(z[kNu * k + i] * scale, ocp.u_min_radps(i), ocp.u_max_radps(i));
    }
  }
  result.cost = OcpCost(ocp, x0, result.u, &result.x);
  if (code == NLOPT_MAXEVAL_REACHED || code == NLOPT_MAXTIME_REACHED) {
    result.status = ControlStatus::kMaxIterations;
  } else if (code < 0 && code != NLOPT_ROUNDOFF_LIMITED) {
    result.status = ControlStatus::kQpFailure;
  }
  if (!std::isfinite(result.cost)) result.status = ControlStatus::kNonFinite;
  return result;
}

namespace {

// NloptSolve behind the OcpSolver interface.
class NloptSolver final : public OcpSolver {
 public:
  explicit NloptSolver(const NloptSettings& settings) : settings_(settings) {}

  OcpSolution Solve(const Ocp& ocp, const StateVector& x0,
                    const std::vector<InputVector>& u_guess) override {
    NloptResult r = NloptSolve(ocp, x0, u_guess, settings_);
    return {r.status, std::move(r.u), std::move(r.x), r.cost};
  }

  std::unique_ptr<OcpSolver> Clone() const override { return std::make_unique<NloptSolver>(*this); }

 private:
  NloptSettings settings_;
};

}  // namespace

std::unique_ptr<OcpSolver> MakeNloptSolver(const OcpSolverSettings& settings) {
  return std::make_unique<NloptSolver>(settings.nlopt);
}

}  // namespace hpa
