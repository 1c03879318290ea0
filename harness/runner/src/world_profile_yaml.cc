#include "hpa/scenarios/world_profile_yaml.h"

#include <cmath>
#include <map>
#include <mutex>

#include "hpa/models/data_dir.h"
#include "hpa/models/input_error.h"
#include "hpa/models/param_yaml.h"
#include "hpa/models/yaml_reader.h"

namespace hpa {
namespace {

// Reads `section` of `map` through `table` when present.
template <class C>
void ReadSection(const YamlMap& map, const ParamTable<C>& table, C* config) {
  if (map.Has(table.section)) ReadParamTable(map.Map(table.section), table, config);
}

// The rate loop: `px4` (which loop the flight code flies), then PX4's parameters; the vehicle's
// rate gyro follows it (present with PX4's loop, at its rate).
void ReadRateLoop(const YamlMap& map, WorldProfileSpec* spec) {
  if (map.Has("rate_loop")) {
    const YamlMap m = map.Map("rate_loop");
    RateLoopSpec& r = spec->rate_loop;
    r.px4 = m.Bool("px4", r.px4);
    ReadParamTable(m, Px4RateParamTable(), &r.params);
    // the gyro is sampled on the physics clock (1 kHz): a whole number of steps per sample
    const double steps = 1000.0 / r.params.rate_hz;
    if (std::abs(steps - std::round(steps)) > 1e-9) {
      m.Fail("rate_hz", "a rate that divides the 1000 Hz physics rate (1000, 500, 250, ...)");
    }
  }
  spec->world.rate_gyro.enabled = spec->rate_loop.px4;
  spec->world.rate_gyro.rate_hz = spec->rate_loop.params.rate_hz;
}

}  // namespace

const std::vector<std::string>& WorldProfileNames() {
  static const std::vector<std::string> names{"ideal", "flight"};
  return names;
}

void ReadWorldProfileSections(const YamlMap& map, WorldProfileSpec* spec) {
  sim::WorldProfile& p = spec->world;
  ReadSection(map, sim::ContactParams(), &p.contact);
  ReadSection(map, sim::ActuationParams(), &p.actuation);
  ReadSection(map, sim::LatencyParams(), &p.latency);
  ReadSection(map, sim::MismatchParams(), &p.mismatch);
  ReadSection(map, sim::AeroParams(), &p.aero);
  ReadSection(map, sim::WindParams(), &p.wind);
  ReadSection(map, sim::VioDriftParams(), &p.vio);
  ReadSection(map, sim::ImuParams(), &p.imu);
  if (map.Has("camera")) {
    const YamlMap m = map.Map("camera");
    ReadParamTable(m, sim::CameraImageParams(), &p.camera);
    if (p.camera.motion_blur_subframes == 1) {
      m.Fail("motion_blur_subframes", "0 (fast approximation) or at least 2 sub-frames");
    }
  }
  ReadRateLoop(map, spec);
}

WorldProfileSpec LoadWorldProfile(const std::string& name) {
  static std::mutex mutex;
  static std::map<std::string, WorldProfileSpec> cache;
  std::lock_guard<std::mutex> lock(mutex);
  if (auto it = cache.find(name); it != cache.end()) return it->second;
  bool known = false;
  for (const std::string& n : WorldProfileNames()) known = known || n == name;
  if (!known) throw InputError("", "world.profile", "unknown profile '" + name + "'");
  const std::string file = DataPath("models/profiles/" + name + ".yaml");
  const YamlMap root = YamlMap::LoadFile(file);
  WorldProfileSpec spec;
  spec.world.name = name;
  ReadWorldProfileSections(root, &spec);
  root.RejectUnknownKeys();
  cache[name] = spec;
  return spec;
}

std::string WorldProfileMarkdown(const std::string& name) {
  const WorldProfileSpec spec = LoadWorldProfile(name);
  const sim::WorldProfile& w = spec.world;
  const std::string header = "`" + name + "`";
  std::string md;
  const auto section = [&](const auto& table, const auto& values) {
    md += "\n### `world." + table.section + "`: " + table.description + "\n\n" +
          ParamTableMarkdown(table, values, "", header);
  };
  section(sim::ContactParams(), w.contact);
  section(sim::ActuationParams(), w.actuation);
  section(sim::LatencyParams(), w.latency);
  section(sim::MismatchParams(), w.mismatch);
  section(sim::AeroParams(), w.aero);
  section(sim::WindParams(), w.wind);
  section(sim::VioDriftParams(), w.vio);
  section(sim::ImuParams(), w.imu);
  section(sim::CameraImageParams(), w.camera);
  md += "\n### `world.rate_loop`: the flight code's body-rate loop (PX4's when `px4: " +
        std::string(spec.rate_loop.px4 ? "true" : "false") + "`)\n\n" +
        ParamTableMarkdown(Px4RateParamTable(), spec.rate_loop.params, "", header);
  return md;
}

}  // namespace hpa
