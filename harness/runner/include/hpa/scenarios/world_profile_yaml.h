#pragma once
// The realism profiles of the simulated world (models/profiles/<name>.yaml) and a scenario's
// `world:` overrides of single numbers in them. Each section is read through its declared
// ParamTable (sim/world_profile.h; the rate loop's, flight code's, autopilot/px4_rate_controller.h).

#include <string>
#include <vector>

#include "hpa/autopilot/autopilot.h"
#include "hpa/sim/world_profile.h"

namespace hpa {

class YamlMap;

/// A profile as a file gives it: the world's parts, and the flight code's rate loop.
struct WorldProfileSpec {
  sim::WorldProfile world;
  RateLoopSpec rate_loop;
};

/// Names of the shipped profiles: ideal | flight.
const std::vector<std::string>& WorldProfileNames();

/// Loads models/profiles/<name>.yaml (cached after the first load); throws InputError naming the
/// file and key for an unknown name or a bad file.
WorldProfileSpec LoadWorldProfile(const std::string& name);

/// Reads the profile sections present in `map` (contact, actuation, latency, mismatch, aero,
/// wind, vio, imu, camera, rate_loop) over `spec`: a key that is absent keeps its value. Unknown
/// keys inside a section are InputErrors listing the valid ones; the caller rejects unknown keys
/// of `map` itself.
void ReadWorldProfileSections(const YamlMap& map, WorldProfileSpec* spec);

/// Every section's declared keys as Markdown, with the values of the profile `name`.
std::string WorldProfileMarkdown(const std::string& name);

}  // namespace hpa
