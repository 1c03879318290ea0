#pragma once
// A controller's own settings, as an MJPC task keeps its own parameters: each registered
// controller declares the keys of the scenario's `controller:` block it reads (its
// ControllerRegistration::settings, in its own file); the scenario keeps the values it wrote by
// key, and the YAML reader, the protocol's JSON and `hpa schema` walk the declarations.

#include <functional>
#include <map>
#include <string>
#include <variant>
#include <vector>

namespace hpa {

/// One value of a setting: a number, a switch or a name.
using SettingValue = std::variant<double, bool, std::string>;

/// One setting a controller declares.
struct SettingDecl {
  std::string key;             // as written in the controller block
  std::string unit;            // "-" for a pure number, "" for a switch or a name
  SettingValue default_value;  // its type is the setting's kind
  double min = 0.0;            // a number's allowed range
  double max = 0.0;
  std::function<std::vector<std::string>()> choices;  // a name's accepted values
  std::string description;                            // one line
};

/// The values a scenario wrote, by key; a key it did not write takes its declaration's default.
using ControllerSettings = std::map<std::string, SettingValue>;

/// A setting's value as text ("1", "true", "rti").
std::string SettingText(const SettingValue& value);

/// Checks `value` against `decl` (its kind, range or choices); throws std::invalid_argument
/// "PREFIXkey: expected ..., got ..." naming what is allowed.
void CheckSetting(const SettingDecl& decl, const SettingValue& value, const std::string& prefix);

/// The declaration of `key` in `decls`, or nullptr.
const SettingDecl* FindSetting(const std::vector<SettingDecl>& decls, const std::string& key);

/// The value of the declared setting `decl` in `settings` (its default when absent).
const SettingValue& SettingOr(const ControllerSettings& settings, const SettingDecl& decl);

}  // namespace hpa
