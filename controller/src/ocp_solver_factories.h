#pragma once
// Factories of the built-in OCP solvers, listed once by ocp_solver.cc; private to the controller
// library.

#include <memory>

#include "hpa/controller/ocp_solver.h"

namespace hpa {

/// RTI: one globalised Gauss-Newton SQP iteration per Solve (RtiIteration).
std::unique_ptr<OcpSolver> MakeRtiSolver(const OcpSolverSettings& settings);
/// NLopt: a fully converged solve per Solve (NloptSolve).
std::unique_ptr<OcpSolver> MakeNloptSolver(const OcpSolverSettings& settings);

}  // namespace hpa
