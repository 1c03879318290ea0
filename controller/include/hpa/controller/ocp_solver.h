#pragma once
// The interface every optimal-control solver offers an MPC, and the one list of solvers (MJPC's
// planner registry habit): controller.solver in a scenario names an entry, HpaMpc makes its
// solver from it, and the scenario validator reads the names (OcpSolverNames). A new solver is
// its own files plus one line in ocp_solver.cc (or a RegisterOcpSolver call).

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hpa/controller/controller.h"
#include "hpa/controller/nlopt_solver.h"
#include "hpa/controller/ocp.h"
#include "hpa/controller/rti_solver.h"

namespace hpa {

/// What one solve returns: a plan inside the input bounds, its simulated states and a status.
struct OcpSolution {
  ControlStatus status = ControlStatus::kSuccess;  // kSuccess / kMaxIterations: plan usable
  std::vector<InputVector> u;                      // plan inputs  (N)
  std::vector<StateVector> x;                      // states simulated with u from x0  (N + 1)
  double cost = 0.0;                               // OCP cost of the plan
};

/// An optimal-control solver: takes the plain Ocp (OCS2 habit), knows nothing of the MPC.
class OcpSolver {
 public:
  virtual ~OcpSolver() = default;
  /// Solves `ocp` from x0, warm-started at u_guess (N inputs; clamped into the bounds).
  virtual OcpSolution Solve(const Ocp& ocp, const StateVector& x0,
                            const std::vector<InputVector>& u_guess) = 0;
  /// Solve into `solution`, reusing its vectors' memory (the RTI solver then allocates nothing
  /// in steady state); the default calls Solve.
  virtual void SolveInto(const Ocp& ocp, const StateVector& x0,
                         const std::vector<InputVector>& u_guess, OcpSolution* solution) {
    *solution = Solve(ocp, x0, u_guess);
  }
  /// A copy with the same settings and internal state (controllers holding one are copyable).
  virtual std::unique_ptr<OcpSolver> Clone() const = 0;
};

/// Settings of the built-in solvers; each solver reads its own.
struct OcpSolverSettings {
  RtiSettings rti;      // globalisation of the rti solver
  NloptSettings nlopt;  // stopping rules of the nlopt solver
};

/// Builds a solver from the settings.
using OcpSolverFactory = std::function<std::unique_ptr<OcpSolver>(const OcpSolverSettings&)>;

/// One registered solver.
struct OcpSolverRegistration {
  std::string name;         // as written in scenarios (controller.solver)
  std::string description;  // one line for --help
  OcpSolverFactory make;    // builds it
};

/// Every registered solver, in registration order (built-ins first: rti, nlopt).
const std::vector<OcpSolverRegistration>& OcpSolvers();
/// The registration named `name`, or nullptr.
const OcpSolverRegistration* FindOcpSolver(const std::string& name);
/// Builds the solver named `name`; throws std::invalid_argument naming the known ones.
std::unique_ptr<OcpSolver> MakeOcpSolver(const std::string& name,
                                         const OcpSolverSettings& settings);
/// Adds a solver at run time (tests, plugins); throws std::invalid_argument on an empty or
/// duplicate name or a missing factory.
void RegisterOcpSolver(OcpSolverRegistration registration);

}  // namespace hpa
