#include "hpa/scenarios/world_profile_yaml.h"

#include <map>
#include <mutex>

#include "hpa/models/input_error.h"
#include "hpa/models/yaml_reader.h"

namespace hpa {

const std::vector<std::string>& WorldProfileNames() {
  static const std::vector<std::string> names{"ideal", "flight"};
  return names;
}

void ReadWorldProfileSections(const YamlMap& map, sim::WorldProfile* profile) {
  if (map.Has("contact")) {
    const YamlMap m = map.Map("contact");
    profile->contact.enabled = m.Bool("enabled", profile->contact.enabled);
    m.RejectUnknownKeys();
  }
  if (map.Has("actuation")) {
    const YamlMap m = map.Map("actuation");
    sim::ActuationProfile& a = profile->actuation;
    a.enabled = m.Bool("enabled", a.enabled);
    a.thrust_coefficient_spread =
        m.Number("thrust_coefficient_spread", 0.0, 0.3, a.thrust_coefficient_spread);
    a.torque_coefficient_spread =
        m.Number("torque_coefficient_spread", 0.0, 0.3, a.torque_coefficient_spread);
    // at most a pack flat in 100 s: the scenarios are tens of seconds
    a.battery_voltage_drop_per_s =
        m.Number("battery_voltage_drop_per_s", 0.0, 0.01, a.battery_voltage_drop_per_s);
    m.RejectUnknownKeys();
  }
  if (map.Has("latency")) {
    const YamlMap m = map.Map("latency");
    sim::LatencyProfile& l = profile->latency;
    l.compute_s = m.Number("compute_s", 0.0, 0.1, l.compute_s);
    l.transport_s = m.Number("transport_s", 0.0, 0.1, l.transport_s);
    l.estimate_s = m.Number("estimate_s", 0.0, 0.1, l.estimate_s);
    m.RejectUnknownKeys();
  }
  if (map.Has("mismatch")) {
    const YamlMap m = map.Map("mismatch");
    sim::MismatchProfile& x = profile->mismatch;
    x.enabled = m.Bool("enabled", x.enabled);
    x.payload_mass_sigma_kg = m.Number("payload_mass_sigma_kg", 0.0, 0.05, x.payload_mass_sigma_kg);
    x.cable_length_sigma_m = m.Number("cable_length_sigma_m", 0.0, 0.1, x.cable_length_sigma_m);
    x.quad_mass_sigma_kg = m.Number("quad_mass_sigma_kg", 0.0, 0.2, x.quad_mass_sigma_kg);
    x.inertia_sigma_fraction =
        m.Number("inertia_sigma_fraction", 0.0, 0.3, x.inertia_sigma_fraction);
    x.thrust_coefficient_sigma_fraction = m.Number("thrust_coefficient_sigma_fraction", 0.0, 0.2,
                                                   x.thrust_coefficient_sigma_fraction);
    x.camera_position_sigma_m =
        m.Number("camera_position_sigma_m", 0.0, 0.05, x.camera_position_sigma_m);
    x.camera_angle_sigma_rad =
        m.Number("camera_angle_sigma_rad", 0.0, 0.2, x.camera_angle_sigma_rad);
    m.RejectUnknownKeys();
  }
}

sim::WorldProfile LoadWorldProfile(const std::string& name) {
  static std::mutex mutex;
  static std::map<std::string, sim::WorldProfile> cache;
  std::lock_guard<std::mutex> lock(mutex);
  if (auto it = cache.find(name); it != cache.end()) return it->second;
  bool known = false;
  for (const std::string& n : WorldProfileNames()) known = known || n == name;
  if (!known) throw InputError("", "world.profile", "unknown profile '" + name + "'");
  const std::string file = std::string(HPA_SOURCE_DIR) + "/models/profiles/" + name + ".yaml";
  const YamlMap root = YamlMap::LoadFile(file);
  sim::WorldProfile profile;
  profile.name = name;
  ReadWorldProfileSections(root, &profile);
  root.RejectUnknownKeys();
  cache[name] = profile;
  return profile;
}

}  // namespace hpa
