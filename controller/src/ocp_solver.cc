#include "hpa/controller/ocp_solver.h"

#include <utility>

#include "hpa/controller/controller_registry.h"
#include "hpa/models/registry.h"

namespace hpa {

// Factories of the built-in solvers, each defined in its solver's own file.
std::unique_ptr<OcpSolver> MakeRtiSolver(const OcpSolverSettings& settings);
std::unique_ptr<OcpSolver> MakeNloptSolver(const OcpSolverSettings& settings);

namespace {

// The built-in solvers, one line each.
Registry<OcpSolverRegistration>& TheRegistry() {
  static Registry<OcpSolverRegistration> registry(
      "OCP solver",
      {
          {"rti", "one globalised Gauss-Newton SQP iteration per call (real-time iteration)",
           MakeRtiSolver},
          {"nlopt", "fully converged NMPC solve (NLopt L-BFGS, adjoint gradient); not real-time",
           MakeNloptSolver},
      });
  return registry;
}

}  // namespace

const std::vector<OcpSolverRegistration>& OcpSolvers() { return TheRegistry().All(); }

const OcpSolverRegistration* FindOcpSolver(const std::string& name) {
  return TheRegistry().Find(name);
}

std::vector<std::string> OcpSolverNames() { return TheRegistry().Names(); }

std::unique_ptr<OcpSolver> MakeOcpSolver(const std::string& name,
                                         const OcpSolverSettings& settings) {
  return TheRegistry().Get(name, "controller.solver").make(settings);
}

void RegisterOcpSolver(OcpSolverRegistration registration) {
  TheRegistry().Add(std::move(registration));
}

}  // namespace hpa
