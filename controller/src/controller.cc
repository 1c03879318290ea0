#include "hpa/controller/controller.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hpa/controller/controller_registry.h"
#include "hpa/controller/rti_solver.h"

namespace hpa {
namespace {

std::string Joined(const std::vector<std::string>& names) {
  std::string joined;
  for (const std::string& name : names) joined += (joined.empty() ? "" : ", ") + name;
  return joined;
}

}  // namespace

BodyRateCommand LevelOutCommand(const Params& params, const Eigen::Quaterniond& q_WB,
                                double attitude_gain_per_s) {
  BodyRateCommand command;
  command.thrust_N = params.HoverThrustN();
  if (!q_WB.coeffs().allFinite() || q_WB.norm() < 1e-9) return command;
  const Eigen::Quaterniond q = q_WB.normalized();
  const Eigen::Vector3d z_B_W = q * Eigen::Vector3d::UnitZ();
  const double tilt_rad = std::acos(std::clamp(z_B_W.z(), -1.0, 1.0));
  // rotation taking body z to world z, in the body frame: axis (z_B x e3) in world
  const Eigen::Vector3d axis_W = z_B_W.cross(Eigen::Vector3d::UnitZ());
  if (axis_W.norm() > 1e-9) {
    const Eigen::Vector3d error_B = q.conjugate() * (axis_W.normalized() * tilt_rad);
    command.w_B_radps = attitude_gain_per_s * error_B;
    command.w_B_radps.z() = 0.0;
  }
  return command;
}

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

const ParamTable<ControllerConfig>& ControllerParamTable() {
  using C = ControllerConfig;
  static const ParamTable<C> t{
      "controller",
      "the high-level controller",
      {{"perception_weight", "-", 0.0, 1e3,
        "scale on the tuned L_cam weights (1: as tuned, 0: L_cam off)", &C::perception_weight},
       {"predict_retaut", "", 0, 0, "hpa_mpc: predict the slack-to-taut guard in the horizon",
        &C::predict_retaut}}};
  return t;
}

std::unique_ptr<Controller> MakeController(const ControllerConfig& config, const Params& params,
                                           std::shared_ptr<const Reference> reference) {
  if (!reference) throw std::invalid_argument("MakeController: null reference");
  CheckParamTable(ControllerParamTable(), "controller.", config);
  const std::vector<std::string> solvers = OcpSolverNames();
  if (std::find(solvers.begin(), solvers.end(), config.solver) == solvers.end()) {
    throw std::invalid_argument("controller.solver: expected one of " + Joined(solvers) +
                                ", got '" + config.solver + "'");
  }
  ParseRtiQpMethod(config.qp_method);  // throws naming the known methods
  const ControllerRegistration* registration = FindController(config.type);
  if (registration == nullptr) {
    throw std::invalid_argument("controller.type: expected one of " + Joined(ControllerNames()) +
                                ", got '" + config.type + "'");
  }
  return registration->make(config, params, std::move(reference));
}

}  // namespace hpa
