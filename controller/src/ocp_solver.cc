#include "hpa/controller/ocp_solver.h"

#include <stdexcept>
#include <utility>

#include "hpa/controller/controller_registry.h"
#include "ocp_solver_factories.h"

namespace hpa {
namespace {

// The built-in solvers, one line each.
std::vector<OcpSolverRegistration> BuiltInOcpSolvers() {
  return {
      {"rti", "one globalised Gauss-Newton SQP iteration per call (real-time iteration)",
       MakeRtiSolver},
      {"nlopt", "fully converged NMPC solve (NLopt L-BFGS, adjoint gradient); not real-time",
       MakeNloptSolver},
  };
}

std::vector<OcpSolverRegistration>& Registry() {
  static std::vector<OcpSolverRegistration> registry = BuiltInOcpSolvers();
  return registry;
}

}  // namespace

const std::vector<OcpSolverRegistration>& OcpSolvers() { return Registry(); }

const OcpSolverRegistration* FindOcpSolver(const std::string& name) {
  for (const OcpSolverRegistration& registration : Registry()) {
    if (registration.name == name) return &registration;
  }
  return nullptr;
}

std::vector<std::string> OcpSolverNames() {
  std::vector<std::string> names;
  for (const OcpSolverRegistration& registration : Registry()) names.push_back(registration.name);
  return names;
}

std::unique_ptr<OcpSolver> MakeOcpSolver(const std::string& name,
                                         const OcpSolverSettings& settings) {
  const OcpSolverRegistration* registration = FindOcpSolver(name);
  if (registration == nullptr) {
    std::string known;
    for (const std::string& n : OcpSolverNames()) known += (known.empty() ? "" : ", ") + n;
    throw std::invalid_argument("controller.solver: expected one of " + known + ", got '" + name +
                                "'");
  }
  return registration->make(settings);
}

void RegisterOcpSolver(OcpSolverRegistration registration) {
  if (registration.name.empty()) {
    throw std::invalid_argument("RegisterOcpSolver: empty solver name");
  }
  if (!registration.make) {
    throw std::invalid_argument("RegisterOcpSolver: solver '" + registration.name +
                                "' has no factory");
  }
  if (FindOcpSolver(registration.name) != nullptr) {
    throw std::invalid_argument("RegisterOcpSolver: solver '" + registration.name +
                                "' is already registered");
  }
  Registry().push_back(std::move(registration));
}

}  // namespace hpa
