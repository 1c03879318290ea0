#pragma once
// The one list of high-level controllers (MJPC's LoadPlanners habit): the scenario validator,
// `hpa --help`, the runner and sweeps read it; a new controller is its own files plus one line
// in controller_registry.cc (or a RegisterController call from a test or plugin).

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hpa/controller/controller.h"

namespace hpa {

/// Builds a controller from its typed config, the flight params and the payload reference.
using ControllerFactory = std::function<std::unique_ptr<Controller>(
    const ControllerConfig&, const Params&, std::shared_ptr<const Reference>)>;

/// One registered controller.
struct ControllerRegistration {
  std::string name;         // as written in scenarios (controller.type)
  std::string description;  // one line for --help
  std::string estimator;    // estimator variant it flies with unless the scenario says otherwise
  ControllerFactory make;   // builds it
  // the keys of the scenario's controller block it reads, declared in its own file (none: it
  // takes no settings)
  std::vector<SettingDecl> settings = {};
};

/// Every registered controller, in registration order (built-ins first).
const std::vector<ControllerRegistration>& Controllers();
/// The registration named `name`, or nullptr.
const ControllerRegistration* FindController(const std::string& name);
/// Names of all registered controllers, in order.
std::vector<std::string> ControllerNames();
/// Adds a controller at run time (tests, plugins); throws std::invalid_argument on an empty or
/// duplicate name or a missing factory.
void RegisterController(ControllerRegistration registration);

/// The declaration of setting `key` for a controller block of type `type`: its own, or else the
/// first registered controller's that declares `key` (a setting meant for another controller,
/// as when `hpa compare` flies one scenario with several); nullptr when no controller declares
/// it.
const SettingDecl* FindControllerSetting(const std::string& type, const std::string& key);

/// Every key some registered controller declares, each once, in registration order.
std::vector<std::string> ControllerSettingKeys();

/// Names of the optimal-control solvers an MPC controller accepts (controller.solver), read
/// from the solver registry of ocp_solver.h (OcpSolvers).
std::vector<std::string> OcpSolverNames();

}  // namespace hpa
