#pragma once
// Real-time iteration (the paper's acados scheme): one Gauss-Newton SQP iteration per call.
// Single shooting: the guess is simulated from x0 (so the trajectory is dynamically exact),
// linearised with HybridModel::StepJacobians, condensed onto the 4N rotor speeds and the
// box QP (rotor bounds) is solved in-house; the full step is taken.

#include <vector>

#include "hpa/controller/box_qp.h"
#include "hpa/controller/controller.h"
#include "hpa/controller/ocp.h"
#include "hpa/models/hybrid_model.h"

namespace hpa {

/// Result of one RTI (or of an iterated Gauss-Newton solve).
struct RtiResult {
  ControlStatus status = ControlStatus::kSuccess;
  BoxQpResult qp;              // the last QP's outcome
  std::vector<InputVector> u;  // new plan inputs, inside the bounds  (N)
  std::vector<StateVector> x;  // states simulated with u from x0  (N + 1)
  double cost = 0.0;           // OCP cost of the new plan
  double cost_guess = 0.0;     // OCP cost of the guess (the linearisation point)
};

/// One Gauss-Newton SQP iteration from u_guess (N inputs; clamped into the bounds first).
/// On QP failure or non-finite numbers: status kQpFailure / kNonFinite and u = the guess.
RtiResult RtiIteration(const Ocp& ocp, const HybridModel& model, const StateVector& x0,
                       const std::vector<InputVector>& u_guess);

}  // namespace hpa
