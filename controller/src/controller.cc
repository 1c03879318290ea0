#include "hpa/controller/controller.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hpa/controller/controller_registry.h"
#include "hpa/models/param_table.h"

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

std::string SettingText(const SettingValue& value) {
  if (const auto* n = std::get_if<std::string>(&value)) return *n;
  if (const auto* b = std::get_if<bool>(&value)) return ParamValueText(*b);
  return ParamValueText(std::get<double>(value));
}

void CheckSetting(const SettingDecl& decl, const SettingValue& value, const std::string& prefix) {
  const std::string what = prefix + decl.key + ": expected ";
  if (value.index() != decl.default_value.index()) {
    static const char* kKinds[] = {"a number", "true or false", "a name"};
    throw std::invalid_argument(what + kKinds[decl.default_value.index()] + ", got '" +
                                SettingText(value) + "'");
  }
  if (const auto* x = std::get_if<double>(&value)) {
    if (!(*x >= decl.min && *x <= decl.max)) {
      throw std::invalid_argument(what + SettingText(decl.min) + " to " + SettingText(decl.max) +
                                  ", got " + SettingText(value));
    }
  } else if (const auto* name = std::get_if<std::string>(&value); name && decl.choices) {
    const std::vector<std::string> choices = decl.choices();
    if (std::find(choices.begin(), choices.end(), *name) == choices.end()) {
      throw std::invalid_argument(what + "one of " + Joined(choices) + ", got '" + *name + "'");
    }
  }
}

const SettingDecl* FindSetting(const std::vector<SettingDecl>& decls, const std::string& key) {
  for (const SettingDecl& d : decls) {
    if (d.key == key) return &d;
  }
  return nullptr;
}

const SettingValue& SettingOr(const ControllerSettings& settings, const SettingDecl& decl) {
  const auto it = settings.find(decl.key);
  return it == settings.end() ? decl.default_value : it->second;
}

namespace {

// The value of the flown controller's setting `key`, which must be of kind T.
template <class T>
T FlownSetting(const ControllerConfig& config, const std::string& key) {
  const ControllerRegistration* registration = FindController(config.type);
  const SettingDecl* decl =
      registration == nullptr ? nullptr : FindSetting(registration->settings, key);
  if (decl == nullptr || !std::holds_alternative<T>(decl->default_value)) {
    throw std::invalid_argument("controller." + key + ": not a setting of " + config.type);
  }
  const SettingValue& value = SettingOr(config.settings, *decl);
  CheckSetting(*decl, value, "controller.");
  return std::get<T>(value);
}

}  // namespace

double ControllerConfig::Number(const std::string& key) const {
  return FlownSetting<double>(*this, key);
}

bool ControllerConfig::Switch(const std::string& key) const {
  return FlownSetting<bool>(*this, key);
}

std::string ControllerConfig::Name(const std::string& key) const {
  return FlownSetting<std::string>(*this, key);
}

std::unique_ptr<Controller> MakeController(const ControllerConfig& config, const Params& params,
                                           std::shared_ptr<const Reference> reference) {
  if (!reference) throw std::invalid_argument("MakeController: null reference");
  const ControllerRegistration* registration = FindController(config.type);
  if (registration == nullptr) {
    throw std::invalid_argument("controller.type: expected one of " + Joined(ControllerNames()) +
                                ", got '" + config.type + "'");
  }
  // the keys this controller reads; a key only another controller declares is that one's
  for (const SettingDecl& d : registration->settings) {
    CheckSetting(d, SettingOr(config.settings, d), "controller.");
  }
  return registration->make(config, params, std::move(reference));
}

}  // namespace hpa
