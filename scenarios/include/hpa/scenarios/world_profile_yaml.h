#pragma once
// The realism profiles of the simulated world (models/profiles/<name>.yaml) and a scenario's
// `world:` overrides of single numbers in them.

#include <string>
#include <vector>

#include "hpa/sim/world_profile.h"

namespace hpa {

class YamlMap;

/// Names of the shipped profiles: ideal | flight.
const std::vector<std::string>& WorldProfileNames();

/// Loads models/profiles/<name>.yaml (cached after the first load); throws InputError naming the
/// file and key for an unknown name or a bad file.
sim::WorldProfile LoadWorldProfile(const std::string& name);

/// Reads the profile sections present in `map` (contact, actuation, latency, mismatch, aero,
/// wind, vio, imu, camera, rate_loop) over `profile`: a key that is absent keeps the profile's
/// value. Unknown keys inside a section are InputErrors; the caller rejects unknown keys of `map`
/// itself.
void ReadWorldProfileSections(const YamlMap& map, sim::WorldProfile* profile);

}  // namespace hpa
