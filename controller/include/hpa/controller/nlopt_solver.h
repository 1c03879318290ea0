#pragma once
// Fully converged NMPC solve of the same OCP with NLopt (L-BFGS with box bounds on the 4N
// rotor speeds, exact gradient by the adjoint through Ocp::StepJacobians). Used to
// check RTI's answer and selectable by ControllerConfig::solver == "nlopt". Not real-time.

#include <vector>

#include "hpa/controller/controller.h"
#include "hpa/controller/ocp.h"

namespace hpa {

/// Stopping rules of the NLopt solve.
struct NloptSettings {
  int max_evaluations = 400;  // cost + gradient evaluations
  double ftol_rel = 1e-10;    // relative cost change
  double xtol_rel = 1e-8;     // relative change of the (hover-normalised) rotor speeds
  double max_time_s = 0.0;    // wall-clock cap per solve; 0 = none (a cap breaks determinism)
};

/// Result of an NLopt solve.
struct NloptResult {
  ControlStatus status = ControlStatus::kSuccess;  // kMaxIterations at the eval/time cap
  int nlopt_code = 0;                              // nlopt_result
  int evaluations = 0;                             // cost + gradient evaluations used
  std::vector<InputVector> u;                      // optimal inputs  (N)
  std::vector<StateVector> x;                      // simulated states  (N + 1)
  double cost = 0.0;                               // OCP cost at u
};

/// Minimises the OCP cost over the rotor speeds from u_guess (clamped into the bounds).
/// On NLopt failure: status kQpFailure (the solver failed), u = the best point found.
NloptResult NloptSolve(const Ocp& ocp, const StateVector& x0,
                       const std::vector<InputVector>& u_guess,
                       const NloptSettings& settings = NloptSettings());

}  // namespace hpa
