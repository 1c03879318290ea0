#include "hpa/controller/controller_registry.h"

#include <algorithm>
#include <utility>

#include "hpa/models/registry.h"

namespace hpa {

// Factories of the built-in controllers, each defined in its controller's own file.
std::unique_ptr<Controller> MakeHpaMpcController(const ControllerConfig&, const Params&,
                                                 std::shared_ptr<const Reference>);
std::unique_ptr<Controller> MakeNonhybridMpcController(const ControllerConfig&, const Params&,
                                                       std::shared_ptr<const Reference>);
std::unique_ptr<Controller> MakeGeometricController(const ControllerConfig&, const Params&,
                                                    std::shared_ptr<const Reference>);
// The settings each built-in controller declares, beside its factory.
std::vector<SettingDecl> HpaMpcSettings();
std::vector<SettingDecl> NonhybridMpcSettings();

namespace {

// The built-in controllers, one line each.
Registry<ControllerRegistration>& TheRegistry() {
  static Registry<ControllerRegistration> registry(
      "controller",
      {
          {"hpa_mpc",
           "hybrid perception-aware NMPC (taut/slack model, L_cam), the paper's controller",
           "hybrid", MakeHpaMpcController, HpaMpcSettings()},
          {"nonhybrid_mpc", "the paper's baseline: always-taut NMPC on the measured payload state",
           "always_taut", MakeNonhybridMpcController, NonhybridMpcSettings()},
          {"geometric", "geometric controller on the quadrotor, payload reference by flatness",
           "hybrid", MakeGeometricController},
      });
  return registry;
}

}  // namespace

const std::vector<ControllerRegistration>& Controllers() { return TheRegistry().All(); }

const ControllerRegistration* FindController(const std::string& name) {
  return TheRegistry().Find(name);
}

std::vector<std::string> ControllerNames() { return TheRegistry().Names(); }

void RegisterController(ControllerRegistration registration) {
  TheRegistry().Add(std::move(registration));
}

const SettingDecl* FindControllerSetting(const std::string& type, const std::string& key) {
  if (const ControllerRegistration* own = FindController(type)) {
    if (const SettingDecl* d = FindSetting(own->settings, key)) return d;
  }
  for (const ControllerRegistration& r : Controllers()) {
    if (const SettingDecl* d = FindSetting(r.settings, key)) return d;
  }
  return nullptr;
}

std::vector<std::string> ControllerSettingKeys() {
  std::vector<std::string> keys;
  for (const ControllerRegistration& r : Controllers()) {
    for (const SettingDecl& d : r.settings) {
      if (std::find(keys.begin(), keys.end(), d.key) == keys.end()) keys.push_back(d.key);
    }
  }
  return keys;
}

}  // namespace hpa
