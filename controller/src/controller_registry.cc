#include "hpa/controller/controller_registry.h"

#include <stdexcept>
#include <utility>

#include "controller_factories.h"

namespace hpa {
namespace {

// The built-in controllers, one line each.
std::vector<ControllerRegistration> BuiltInControllers() {
  return {
      {"hpa_mpc", "hybrid perception-aware NMPC (taut/slack model, L_cam), the paper's controller",
       "hybrid", MakeHpaMpcController},
      {"nonhybrid_mpc", "the paper's baseline: always-taut NMPC on the measured payload state",
       "always_taut", MakeNonhybridMpcController},
      {"geometric", "geometric controller on the quadrotor, payload reference by flatness",
       "hybrid", MakeGeometricController},
  };
}

std::vector<ControllerRegistration>& Registry() {
  static std::vector<ControllerRegistration> registry = BuiltInControllers();
  return registry;
}

}  // namespace

const std::vector<ControllerRegistration>& Controllers() { return Registry(); }

const ControllerRegistration* FindController(const std::string& name) {
  for (const ControllerRegistration& registration : Registry()) {
    if (registration.name == name) return &registration;
  }
  return nullptr;
}

std::vector<std::string> ControllerNames() {
  std::vector<std::string> names;
  for (const ControllerRegistration& registration : Registry()) names.push_back(registration.name);
  return names;
}

void RegisterController(ControllerRegistration registration) {
  if (registration.name.empty()) {
    throw std::invalid_argument("RegisterController: empty controller name");
  }
  if (!registration.make) {
    throw std::invalid_argument("RegisterController: controller '" + registration.name +
                                "' has no factory");
  }
  if (FindController(registration.name) != nullptr) {
    throw std::invalid_argument("RegisterController: controller '" + registration.name +
                                "' is already registered");
  }
  Registry().push_back(std::move(registration));
}

}  // namespace hpa
