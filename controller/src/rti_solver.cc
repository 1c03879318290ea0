#include "hpa/controller/rti_solver.h"

#include <cmath>

#include "hpa/controller/condensing.h"

namespace hpa {

RtiResult RtiIteration(const Ocp& ocp, const HybridModel& model, const StateVector& x0,
                       const std::vector<InputVector>& u_guess) {
  const int n = ocp.horizon_steps;
  RtiResult result;
  result.u.resize(n);
  for (int k = 0; k < n; ++k) {
    result.u[k] = u_guess[k].cwiseMax(ocp.u_min_radps).cwiseMin(ocp.u_max_radps);
  }

  // linearise: simulate the guess, sensitivities and Gauss-Newton stage models
  std::vector<StateMatrix> a(n);
  std::vector<InputMatrix> b(n);
  std::vector<StageQuadratic> stages(n + 1);
  std::vector<StateVector> x(n + 1);
  ResidualVector r;
  ResidualStateJacobian r_x;
  ResidualInputJacobian r_u;
  x[0] = x0;
  double cost = 0.0;
  for (int k = 0; k < n; ++k) {
    StageResidual(ocp, k, x[k], result.u[k], &r, &r_x, &r_u);
    cost += r.squaredNorm();
    stages[k] = GaussNewtonStage(r, r_x, r_u);
    model.StepJacobians(x[k], result.u[k], ocp.mode, ocp.stage_dt_s, &x[k + 1], &a[k], &b[k]);
  }
  StageResidual(ocp, n, x[n], InputVector::Zero(), &r, &r_x, &r_u);
  r_u.setZero();
  cost += r.squaredNorm();
  stages[n] = GaussNewtonStage(r, r_x, r_u);
  result.cost_guess = cost;
  result.x = x;
  result.cost = cost;
  if (!std::isfinite(cost)) {
    result.status = ControlStatus::kNonFinite;
    return result;
  }

  // condense and solve the box QP on du
  Eigen::MatrixXd h;
  Eigen::VectorXd g;
  Condense(a, b, stages, &h, &g);
  Eigen::VectorXd lb(kNu * n), ub(kNu * n);
  for (int k = 0; k < n; ++k) {
    lb.segment<kNu>(kNu * k) = ocp.u_min_radps - result.u[k];
    ub.segment<kNu>(kNu * k) = ocp.u_max_radps - result.u[k];
  }
  Eigen::VectorXd du = Eigen::VectorXd::Zero(kNu * n);
  result.qp = SolveBoxQp(h, g, lb, ub, &du);
  if (result.qp.status == BoxQpStatus::kNotPositiveDefinite ||
      result.qp.status == BoxQpStatus::kNonFinite || !du.allFinite()) {
    result.status = result.qp.status == BoxQpStatus::kNonFinite ? ControlStatus::kNonFinite
                                                                : ControlStatus::kQpFailure;
    return result;
  }

  // full step (RTI), then the new plan's exact trajectory and cost
  std::vector<InputVector> u_new(n);
  for (int k = 0; k < n; ++k) {
    // du respects the box by construction; the min/max only removes rounding at the bounds
    u_new[k] = (result.u[k] + du.segment<kNu>(kNu * k))
                   .cwiseMax(ocp.u_min_radps)
                   .cwiseMin(ocp.u_max_radps);
  }
  std::vector<StateVector> x_new;
  const double cost_new = OcpCost(ocp, model, x0, u_new, &x_new);
  if (!std::isfinite(cost_new)) {
    result.status = ControlStatus::kNonFinite;
    return result;
  }
  result.u = u_new;
  result.x = x_new;
  result.cost = cost_new;
  result.status = result.qp.status == BoxQpStatus::kMaxIterations ? ControlStatus::kMaxIterations
                                                                  : ControlStatus::kSuccess;
  return result;
}

}  // namespace hpa
