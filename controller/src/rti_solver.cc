#include "hpa/controller/rti_solver.h"

#include <cmath>
#include <stdexcept>

#include "box_qp.h"
#include "condensing.h"
#include "hpa/controller/ocp_solver.h"
#include "riccati_qp.h"

namespace hpa {

/// The scratch of one RTI: linearisation, stage models, condensed QP and line-search trials.
struct RtiWorkspace::Impl {
  OcpLinearization lin;
  std::vector<StageQuadratic> stages;  // (N + 1)
  CondensingWorkspace condensing;
  BoxQpWorkspace qp;
  RiccatiWorkspace riccati;
  Eigen::MatrixXd h, h_reg;        // condensed Hessian, and with the LM term  (4N x 4N)
  Eigen::VectorXd g, lb, ub, du;   // gradient, step bounds, step  (4N)
  std::vector<InputVector> u_try;  // line-search trial  (N)
  std::vector<StateVector> x_try;  // its states  (N + 1)
};

RtiWorkspace::RtiWorkspace() : impl_(std::make_unique<Impl>()) {}
RtiWorkspace::~RtiWorkspace() = default;
RtiWorkspace::RtiWorkspace(const RtiWorkspace& other)
    : impl_(std::make_unique<Impl>(*other.impl_)) {}
RtiWorkspace& RtiWorkspace::operator=(const RtiWorkspace& other) {
  *impl_ = *other.impl_;
  return *this;
}

namespace {

// Linearises along result->u (simulated states and cost into result) and builds the condensed
// Gauss-Newton QP on du with bounds u_min - u <= du <= u_max - u. False: non-finite cost.
bool BuildQp(const Ocp& ocp, const StateVector& x0, const RtiSettings& settings,
             RtiWorkspace::Impl* w, RtiResult* result) {
  const int n = ocp.horizon_steps;
  LinearizeAlong(ocp, x0, result->u, &w->lin);
  w->stages.resize(n + 1);
  for (int k = 0; k <= n; ++k) {
    GaussNewtonStage(w->lin.r[k], w->lin.r_x[k], w->lin.r_u[k], OcpResidualColumns(),
                     &w->stages[k]);
  }
  result->cost_guess = w->lin.cost;
  result->cost = w->lin.cost;
  result->x = w->lin.x;
  if (!std::isfinite(w->lin.cost)) return false;
  switch (settings.qp_method) {
    case RtiQpMethod::kStructuredCondensing:
      CondenseStructured(w->lin.a, w->lin.b, w->stages, &w->condensing, &w->h, &w->g);
      break;
    case RtiQpMethod::kDenseCondensing:
      Condense(w->lin.a, w->lin.b, w->stages, &w->condensing, &w->h, &w->g);
      break;
    case RtiQpMethod::kRiccati:
      StageQpGradient(w->lin.a, w->lin.b, w->stages, &w->g);  // the stages are the QP
      break;
  }
  w->lb.resize(kNu * n);
  w->ub.resize(kNu * n);
  for (int k = 0; k < n; ++k) {
    w->lb.segment<kNu>(kNu * k) = ocp.u_min_radps - result->u[k];
    w->ub.segment<kNu>(kNu * k) = ocp.u_max_radps - result->u[k];
  }
  return true;
}

// The box QP on du with the Levenberg-Marquardt term shift * I on the input Hessian.
BoxQpResult SolveQp(const RtiSettings& settings, double shift, RtiWorkspace::Impl* w) {
  if (settings.qp_method == RtiQpMethod::kRiccati) {
    return SolveRiccatiBoxQp(w->lin.a, w->lin.b, w->stages, shift, w->lb, w->ub, &w->du,
                             &w->riccati);
  }
  const Eigen::MatrixXd* h_qp = &w->h;
  if (shift > 0.0) {
    w->h_reg = w->h;
    w->h_reg.diagonal().array() += shift;
    h_qp = &w->h_reg;
  }
  return SolveBoxQp(*h_qp, w->g, w->lb, w->ub, &w->du, &w->qp);
}

// Armijo backtracking along w->du from result->u (cost `cost`, directional derivative `slope`):
// true when a step is accepted (result->u, x, cost and step updated).
bool LineSearch(const Ocp& ocp, const StateVector& x0, const RtiSettings& settings, double cost,
                double slope, RtiWorkspace::Impl* w, RtiResult* result) {
  const int n = ocp.horizon_steps;
  w->u_try.resize(n);
  for (double alpha = 1.0; alpha >= settings.min_step; alpha *= 0.5) {
    for (int k = 0; k < n; ++k) {
      // du respects the box by construction; the min/max only removes rounding at the bounds
      w->u_try[k] = (result->u[k] + alpha * w->du.segment<kNu>(kNu * k))
                        .cwiseMax(ocp.u_min_radps)
                        .cwiseMin(ocp.u_max_radps);
    }
    const double cost_try = OcpCost(ocp, x0, w->u_try, &w->x_try);
    ++result->cost_evaluations;
    if (std::isfinite(cost_try) && cost_try <= cost + settings.armijo * alpha * slope) {
      result->u = w->u_try;
      result->x = w->x_try;
      result->cost = cost_try;
      result->step = alpha;
      return true;
    }
  }
  return false;
}

}  // namespace

void RtiIteration(const Ocp& ocp, const StateVector& x0, const std::vector<InputVector>& u_guess,
                  const RtiSettings& settings, RtiWorkspace* workspace, RtiResult* result) {
  RtiWorkspace::Impl* w = &workspace->impl();
  const int n = ocp.horizon_steps;
  *result = RtiResult{ControlStatus::kSuccess, 0, std::move(result->u), std::move(result->x)};
  result->u.resize(n);
  for (int k = 0; k < n; ++k) {
    result->u[k] = u_guess[k].cwiseMax(ocp.u_min_radps).cwiseMin(ocp.u_max_radps);
  }
  if (!BuildQp(ocp, x0, settings, w, result)) {
    result->status = ControlStatus::kNonFinite;
    return;
  }
  const double cost = result->cost;
  const double lm_unit = ocp.weights.r_input.mean() / (ocp.u_hover_radps * ocp.u_hover_radps);
  // LM loop: QP on the regularised Hessian, then backtracking along its du
  double mu = settings.lm_initial;
  bool any_qp_solved = false;
  w->du.resize(kNu * n);
  for (int attempt = 0; attempt < settings.lm_max_tries; ++attempt) {
    if (attempt > 0) mu = mu > 0.0 ? mu * settings.lm_growth : settings.lm_first_increase;
    w->du.setZero();
    const BoxQpResult qp = SolveQp(settings, mu * lm_unit, w);
    result->qp_iterations = qp.iterations;
    ++result->qp_solves;
    if (qp.status == BoxQpStatus::kNotPositiveDefinite || qp.status == BoxQpStatus::kNonFinite ||
        !w->du.allFinite()) {
      continue;  // more regularisation
    }
    any_qp_solved = true;
    // directional derivative of the cost J = sum |r|^2 along du: 2 g^T du
    const double slope = 2.0 * w->g.dot(w->du);
    if (!(slope < 0.0)) break;  // no descent direction: the guess is stationary
    if (LineSearch(ocp, x0, settings, cost, slope, w, result)) {
      result->lm = mu;
      result->status = qp.status == BoxQpStatus::kMaxIterations ? ControlStatus::kMaxIterations
                                                                : ControlStatus::kSuccess;
      return;
    }
  }
  // no step accepted: keep the guess (already in result->u / x / cost)
  result->status = any_qp_solved ? ControlStatus::kSuccess : ControlStatus::kQpFailure;
}

RtiResult RtiIteration(const Ocp& ocp, const StateVector& x0,
                       const std::vector<InputVector>& u_guess, const RtiSettings& settings) {
  RtiWorkspace workspace;
  RtiResult result;
  RtiIteration(ocp, x0, u_guess, settings, &workspace, &result);
  return result;
}

namespace {

// RtiIteration behind the OcpSolver interface, with its scratch kept between solves.
class RtiSolver final : public OcpSolver {
 public:
  explicit RtiSolver(const RtiSettings& settings) : settings_(settings) {}

  OcpSolution Solve(const Ocp& ocp, const StateVector& x0,
                    const std::vector<InputVector>& u_guess) override {
    RtiIteration(ocp, x0, u_guess, settings_, &workspace_, &result_);
    return {result_.status, result_.u, result_.x, result_.cost};
  }

  void SolveInto(const Ocp& ocp, const StateVector& x0, const std::vector<InputVector>& u_guess,
                 OcpSolution* solution) override {
    RtiIteration(ocp, x0, u_guess, settings_, &workspace_, &result_);
    solution->status = result_.status;
    solution->u = result_.u;
    solution->x = result_.x;
    solution->cost = result_.cost;
  }

  std::unique_ptr<OcpSolver> Clone() const override { return std::make_unique<RtiSolver>(*this); }

 private:
  RtiSettings settings_;
  RtiWorkspace workspace_;  // scratch, reused by every solve
  RtiResult result_;        // the last solve's result (its vectors reused)
};

}  // namespace

const std::vector<std::string>& RtiQpMethodNames() {
  static const std::vector<std::string> names = {"structured", "dense", "riccati"};
  return names;
}

RtiQpMethod ParseRtiQpMethod(const std::string& name) {
  if (name == "structured") return RtiQpMethod::kStructuredCondensing;
  if (name == "dense") return RtiQpMethod::kDenseCondensing;
  if (name == "riccati") return RtiQpMethod::kRiccati;
  throw std::invalid_argument(
      "controller.qp_method: expected one of structured, dense, riccati, got '" + name + "'");
}

std::unique_ptr<OcpSolver> MakeRtiSolver(const OcpSolverSettings& settings) {
  return std::make_unique<RtiSolver>(settings.rti);
}

}  // namespace hpa
