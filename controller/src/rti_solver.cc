#include "hpa/controller/rti_solver.h"

#include <cmath>

#include "box_qp.h"
#include "condensing.h"
#include "hpa/controller/ocp_solver.h"

namespace hpa {

RtiResult RtiIteration(const Ocp& ocp, const StateVector& x0,
                       const std::vector<InputVector>& u_guess, const RtiSettings& settings) {
  const int n = ocp.horizon_steps;
  RtiResult result;
  result.u.resize(n);
  for (int k = 0; k < n; ++k) {
    result.u[k] = u_guess[k].cwiseMax(ocp.u_min_radps).cwiseMin(ocp.u_max_radps);
  }

  // linearise along the guess, Gauss-Newton stage models
  OcpLinearization lin = LinearizeAlong(ocp, x0, result.u);
  std::vector<StageQuadratic> stages(n + 1);
  for (int k = 0; k <= n; ++k) stages[k] = GaussNewtonStage(lin.r[k], lin.r_x[k], lin.r_u[k]);
  const double cost = lin.cost;
  result.cost_guess = cost;
  result.x = std::move(lin.x);
  result.cost = cost;
  if (!std::isfinite(cost)) {
    result.status = ControlStatus::kNonFinite;
    return result;
  }

  // condense; the QP on du has bounds u_min - u <= du <= u_max - u
  Eigen::MatrixXd h;
  Eigen::VectorXd g;
  Condense(lin.a, lin.b, stages, &h, &g);
  Eigen::VectorXd lb(kNu * n), ub(kNu * n);
  for (int k = 0; k < n; ++k) {
    lb.segment<kNu>(kNu * k) = ocp.u_min_radps - result.u[k];
    ub.segment<kNu>(kNu * k) = ocp.u_max_radps - result.u[k];
  }
  const double lm_unit = ocp.weights.r_input.mean() / (ocp.u_hover_radps * ocp.u_hover_radps);

  // LM loop: QP on the regularised Hessian, then backtracking along its du
  double mu = settings.lm_initial;
  bool any_qp_solved = false;
  Eigen::MatrixXd h_reg;
  Eigen::VectorXd du(kNu * n);
  std::vector<InputVector> u_try(n);
  std::vector<StateVector> x_try;
  for (int attempt = 0; attempt < settings.lm_max_tries; ++attempt) {
    if (attempt > 0) mu = mu > 0.0 ? mu * settings.lm_growth : settings.lm_first_increase;
    const Eigen::MatrixXd* h_qp = &h;
    if (mu > 0.0) {
      h_reg = h;
      h_reg.diagonal().array() += mu * lm_unit;
      h_qp = &h_reg;
    }
    du.setZero();
    const BoxQpResult qp = SolveBoxQp(*h_qp, g, lb, ub, &du);
    result.qp_iterations = qp.iterations;
    ++result.qp_solves;
    if (qp.status == BoxQpStatus::kNotPositiveDefinite || qp.status == BoxQpStatus::kNonFinite ||
        !du.allFinite()) {
      continue;  // more regularisation
    }
    any_qp_solved = true;
    // directional derivative of the cost J = sum |r|^2 along du: 2 g^T du
    const double slope = 2.0 * g.dot(du);
    if (!(slope < 0.0)) break;  // no descent direction: the guess is stationary
    for (double alpha = 1.0; alpha >= settings.min_step; alpha *= 0.5) {
      for (int k = 0; k < n; ++k) {
        // du respects the box by construction; the min/max only removes rounding at the bounds
        u_try[k] = (result.u[k] + alpha * du.segment<kNu>(kNu * k))
                       .cwiseMax(ocp.u_min_radps)
                       .cwiseMin(ocp.u_max_radps);
      }
      const double cost_try = OcpCost(ocp, x0, u_try, &x_try);
      ++result.cost_evaluations;
      if (std::isfinite(cost_try) && cost_try <= cost + settings.armijo * alpha * slope) {
        result.u = u_try;
        result.x = x_try;
        result.cost = cost_try;
        result.step = alpha;
        result.lm = mu;
        result.status = qp.status == BoxQpStatus::kMaxIterations ? ControlStatus::kMaxIterations
                                                                 : ControlStatus::kSuccess;
        return result;
      }
    }
  }
  // no step accepted: keep the guess (already in result.u / x / cost)
  result.status = any_qp_solved ? ControlStatus::kSuccess : ControlStatus::kQpFailure;
  return result;
}

namespace {

// RtiIteration behind the OcpSolver interface.
class RtiSolver final : public OcpSolver {
 public:
  explicit RtiSolver(const RtiSettings& settings) : settings_(settings) {}

  OcpSolution Solve(const Ocp& ocp, const StateVector& x0,
                    const std::vector<InputVector>& u_guess) override {
    RtiResult r = RtiIteration(ocp, x0, u_guess, settings_);
    return {r.status, std::move(r.u), std::move(r.x), r.cost};
  }

  std::unique_ptr<OcpSolver> Clone() const override { return std::make_unique<RtiSolver>(*this); }

 private:
  RtiSettings settings_;
};

}  // namespace

std::unique_ptr<OcpSolver> MakeRtiSolver(const OcpSolverSettings& settings) {
  return std::make_unique<RtiSolver>(settings.rti);
}

}  // namespace hpa
