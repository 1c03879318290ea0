#pragma once
// Real-time iteration (the paper's acados scheme): one Gauss-Newton SQP iteration per call.
// Single shooting: the guess is simulated from x0 (so the trajectory is dynamically exact),
// linearised by LinearizeAlong (ocp.h), condensed onto the 4N rotor speeds and the
// box QP (rotor bounds) is solved in-house. The step is globalised (why: README): an Armijo
// backtracking line search on the OCP cost (single shooting: every trial is simulated exactly,
// and the box is convex so every trial is feasible), and Levenberg-Marquardt regularisation
// of the Gauss-Newton Hessian, raised when the QP is not positive definite or no step along
// its direction decreases the cost. A call never returns a plan costlier than its guess.

#include <memory>
#include <string>
#include <vector>

#include "hpa/controller/controller.h"
#include "hpa/controller/ocp.h"

namespace hpa {

/// How the RTI solves its QP on the rotor-speed steps (all give the same step up to rounding).
enum class RtiQpMethod {
  kDenseCondensing,       // Condense (every block product dense), then the dense box QP
  kStructuredCondensing,  // CondenseStructured (skips the zero blocks), then the dense box QP
  kRiccati,               // no condensing: active-set box QP with Riccati recursions (riccati_qp.h)
};

/// The names of RtiQpMethod as scenarios write them (controller.qp_method): structured, dense,
/// riccati.
const std::vector<std::string>& RtiQpMethodNames();
/// The method named `name` (one of RtiQpMethodNames()); throws std::invalid_argument naming the
/// known ones.
RtiQpMethod ParseRtiQpMethod(const std::string& name);

/// Globalisation of the RTI step and its QP.
struct RtiSettings {
  RtiQpMethod qp_method = RtiQpMethod::kStructuredCondensing;
  // Levenberg-Marquardt: H + mu * lm_unit * I, lm_unit = the input-cost curvature
  // r_input / u_hover^2 (so mu = 1 doubles the input regularisation). Tries mu = lm_initial,
  // then multiplies by lm_growth up to lm_max_tries QP solves.
  double lm_initial = 0.0;
  double lm_growth = 100.0;
  double lm_first_increase = 1.0;  // mu used on the first increase from lm_initial = 0
  int lm_max_tries = 3;
  // Armijo backtracking on the cost: accept alpha if J(alpha) <= J(0) + armijo * alpha * dJ,
  // dJ = 2 g^T du (< 0 for a descent direction); alpha halves down to min_step.
  double armijo = 1e-4;
  double min_step = 1.0 / 16.0;
};

/// Result of one RTI (or of an iterated Gauss-Newton solve).
struct RtiResult {
  ControlStatus status = ControlStatus::kSuccess;
  int qp_iterations = 0;       // active-set iterations of the last QP
  std::vector<InputVector> u;  // new plan inputs, inside the bounds  (N)
  std::vector<StateVector> x;  // states simulated with u from x0  (N + 1)
  double cost = 0.0;           // OCP cost of the new plan
  double cost_guess = 0.0;     // OCP cost of the guess (the linearisation point)
  double step = 0.0;           // accepted line-search step (0: no descent found, u = guess)
  double lm = 0.0;             // Levenberg-Marquardt mu of the accepted step
  int qp_solves = 0;           // QPs solved (1 + LM increases)
  int cost_evaluations = 0;    // line-search simulations
};

/// Scratch memory of RtiIteration (linearisation, stage models, QP), sized by the first call and
/// reused by the next ones without heap allocation. A copy has the same sizes (a copied controller
/// solves without allocating); the contents are scratch, never read before written.
class RtiWorkspace {
 public:
  /// An empty workspace, sized by the first RtiIteration that uses it.
  RtiWorkspace();
  /// Frees the scratch.
  ~RtiWorkspace();
  /// Copies the scratch (sizes and contents).
  RtiWorkspace(const RtiWorkspace&);
  /// Copies the scratch (sizes and contents).
  RtiWorkspace& operator=(const RtiWorkspace&);

  struct Impl;  // defined in rti_solver.cc
  /// The scratch itself.
  Impl& impl() { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

/// RtiIteration writing into `result` (its vectors reused) with its scratch in `workspace`: once
/// both have seen a call with the same horizon, the call allocates no heap memory.
void RtiIteration(const Ocp& ocp, const StateVector& x0, const std::vector<InputVector>& u_guess,
                  const RtiSettings& settings, RtiWorkspace* workspace, RtiResult* result);

/// One Gauss-Newton SQP iteration from u_guess (N inputs; clamped into the bounds first),
/// globalised per `settings`. Non-finite guess cost: kNonFinite; every QP failing: kQpFailure
/// (u = the guess in both). No descent after all LM tries: kSuccess with step 0 and u = the
/// guess (the guess is then the best plan known; the next call relinearises).
RtiResult RtiIteration(const Ocp& ocp, const StateVector& x0,
                       const std::vector<InputVector>& u_guess,
                       const RtiSettings& settings = RtiSettings());

}  // namespace hpa
