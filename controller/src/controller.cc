#include "hpa/controller/controller.h"

#include <cmath>
#include <stdexcept>

#include "hpa/controller/geometric_controller.h"
#include "hpa/controller/hpa_mpc.h"

namespace hpa {

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
  }
  return "unknown";
}

std::unique_ptr<Controller> MakeController(const ControllerConfig& config, const Params& params,
                                           std::shared_ptr<const Reference> reference) {
  if (!reference) throw std::invalid_argument("MakeController: null reference");
  if (!std::isfinite(config.perception_weight) || config.perception_weight < 0.0) {
    throw std::invalid_argument("controller.perception_weight: expected a finite value >= 0");
  }
  if (config.solver != "rti" && config.solver != "nlopt") {
    throw std::invalid_argument("controller.solver: expected rti or nlopt, got '" + config.solver +
                                "'");
  }
  if (config.type == "geometric") {
    return std::make_unique<GeometricController>(params, std::move(reference));
  }
  if (config.type == "hpa_mpc" || config.type == "nonhybrid_mpc") {
    MpcSettings settings;
    settings.hybrid = (config.type == "hpa_mpc");
    settings.perception_weight = config.perception_weight;
    settings.solver = config.solver;
    return std::make_unique<HpaMpc>(params, std::move(reference), settings);
  }
  throw std::invalid_argument(
      "controller.type: expected hpa_mpc, nonhybrid_mpc or geometric, got '" + config.type + "'");
}

}  // namespace hpa
