#include "hpa/controller/controller.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hpa/controller/controller_registry.h"

namespace hpa {
namespace {

std::string Joined(const std::vector<std::string>& names) {
  std::string joined;
  for (const std::string& name : names) joined += (joined.empty() ? "" : ", ") + name;
  return joined;
}

}  // namespace

const char* ToString(ControlStatus status) {
  switch (status) {
    case ControlStatus::kSuccess:
      return "success";
    case ControlStatus::kMaxIterations:
      return "max_iterations";
    case ControlStatus::kQpFailure:
      return "qp_failure";
    case ControlStatus::kNonFinite:
      return "non_finite";
    case ControlStatus::kFallback:
      return "fallback";
    case ControlStatus::kRecovery:
      return "recovery";
  }
  return "unknown";
}

std::unique_ptr<Controller> MakeController(const ControllerConfig& config, const Params& params,
                                           std::shared_ptr<const Reference> reference) {
  if (!reference) throw std::invalid_argument("MakeController: null reference");
  if (!std::isfinite(config.perception_weight) || config.perception_weight < 0.0) {
    throw std::invalid_argument("controller.perception_weight: expected a finite value >= 0");
  }
  const std::vector<std::string> solvers = OcpSolverNames();
  if (std::find(solvers.begin(), solvers.end(), config.solver) == solvers.end()) {
    throw std::invalid_argument("controller.solver: expected one of " + Joined(solvers) +
                                ", got '" + config.solver + "'");
  }
  const ControllerRegistration* registration = FindController(config.type);
  if (registration == nullptr) {
    throw std::invalid_argument("controller.type: expected one of " + Joined(ControllerNames()) +
                                ", got '" + config.type + "'");
  }
  return registration->make(config, params, std::move(reference));
}

}  // namespace hpa
