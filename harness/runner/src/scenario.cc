#include "hpa/scenarios/scenario.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "hpa/controller/controller_registry.h"
#include "hpa/controller/team_controller.h"
#include "hpa/estimator/estimator_registry.h"
#include "hpa/models/cooperative_model.h"
#include "hpa/models/input_error.h"
#include "hpa/models/param_yaml.h"
#include "hpa/models/params_yaml.h"
#include "hpa/models/yaml_reader.h"
#include "hpa/scenarios/expect_keys.h"
#include "hpa/scenarios/metrics.h"
#include "hpa/scenarios/reference_types.h"
#include "hpa/scenarios/world_profile_yaml.h"
#include "harness/runner/src/events/event_vehicles.h"
#include "harness/runner/src/scenario_set_path.h"

namespace hpa {
namespace {

// The settings a controller block writes: every key some registered controller declares, read
// by the declaration of the block's own type where it has one (a key only another controller
// declares is that one's: `hpa compare` flies one scenario with several controllers).
ControllerSettings ReadControllerSettings(const YamlMap& block, const std::string& type) {
  ControllerSettings settings;
  for (const std::string& key : ControllerSettingKeys()) {
    if (!block.Has(key)) continue;
    const SettingDecl& d = *FindControllerSetting(type, key);
    if (std::holds_alternative<double>(d.default_value)) {
      settings[key] = block.Number(key, d.min, d.max);
    } else if (std::holds_alternative<bool>(d.default_value)) {
      settings[key] = block.Bool(key, std::get<bool>(d.default_value));
    } else if (d.choices) {
      settings[key] = block.Choice(key, d.choices(), std::get<std::string>(d.default_value));
    } else {
      settings[key] = block.String(key, std::get<std::string>(d.default_value));
    }
  }
  return settings;
}

// The run keeps its log in memory (one row per control step): an hour of flight, several
// battery lifetimes, stays in the hundreds of megabytes.
constexpr double kMaxScenarioDuration_s = 3600.0;

ExpectSpec ParseExpect(const YamlMap& e) {
  ExpectSpec x;
  for (const ExpectKey& k : ExpectKeys()) {
    if (!e.Has(k.key)) continue;
    std::vector<double>& bound = x.bounds[k.key];
    if (k.size == 0) {
      bound = {e.Bool(k.key, false) ? 1.0 : 0.0};
    } else if (k.size == 1) {
      bound = {k.integer ? static_cast<double>(
                               e.Integer(k.key, static_cast<long>(k.min), static_cast<long>(k.max)))
                         : e.Number(k.key, k.min, k.max)};
    } else {
      const Eigen::VectorXd v = e.Vector(k.key, k.size, k.min, k.max);
      bound.assign(v.data(), v.data() + v.size());
    }
  }
  e.RejectUnknownKeys();
  return x;
}

// The `payload:` and `vehicles:` blocks of a team scenario; each number within the range
// params.yaml declares for the single vehicle's field it stands for.
TeamSpec ParseTeam(const YamlMap& root) {
  TeamSpec team;
  const ParamDecl<Params>& mass = FindParamDecl(ParamsTables(), &Params::payload_mass_kg);
  const ParamDecl<Params>& length = FindParamDecl(ParamsTables(), &Params::cable_length_m);
  if (root.Has("payload")) {
    const YamlMap p = root.Map("payload");
    team.payload_mass_kg = p.Number("mass_kg", mass.min, mass.max, team.payload_mass_kg);
    if (p.Has("inertia_kgm2"))
      team.payload_inertia_P_kgm2 = p.Vector("inertia_kgm2", 3, 1e-7, 10.0);
    team.payload_on_ground = p.Bool("on_ground", false);
    p.RejectUnknownKeys();
  }
  const YAML::Node list = root.Node("vehicles");
  if (!list.IsSequence() || list.size() < 1 || list.size() > kMaxTeamVehicles) {
    root.Fail("vehicles", "expected a list of 1 to " + std::to_string(kMaxTeamVehicles) +
                              " vehicles (each: cable_length_m, attach_m, start_slack_m)");
  }
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string path = root.KeyPath("vehicles") + "." + std::to_string(i);
    if (!list[i].IsMap()) throw InputError(root.file(), path, "expected a vehicle map");
    const YamlMap v(list[i], root.file(), path);
    VehicleSpec spec;
    spec.cable_length_m = v.Number("cable_length_m", length.min, length.max, spec.cable_length_m);
    // an attachment point on the payload's body: within a metre of its centre
    if (v.Has("attach_m")) {
      spec.p_PA_P_m = v.Vector("attach_m", 3, -1.0, 1.0);
    } else if (list.size() > 1) {
      v.Fail("attach_m",
             "each vehicle of a team says where its cable holds the payload (payload frame, m)");
    }
    spec.start_slack_m = v.Number("start_slack_m", 0.0, spec.cable_length_m, 0.0);
    v.RejectUnknownKeys();
    team.vehicles.push_back(spec);
  }
  return team;
}

// The section of params.yaml that declares `member` ("payload", "cable").
template <class M>
std::string ParamSection(M Params::*member) {
  const ParamDecl<Params>& decl = FindParamDecl(ParamsTables(), member);
  for (const ParamTable<Params>& table : ParamsTables()) {
    for (const ParamDecl<Params>& d : table.params) {
      if (&d == &decl) return table.section;
    }
  }
  throw std::logic_error("a declared parameter outside every table");
}

// A `vehicles:` list of one is the single vehicle (RotorTM's N = 1 model switch: one cable on
// the payload's centre, a point mass): its cable length and the payload's mass become the
// scenario's params (the flight code's and the world's alike), and the scenario flies the
// single-vehicle program. What only a rigid payload under several cables has (an attachment
// point off the centre, an inertia, a start with a slack cable or on the ground) is refused,
// naming the key.
void AsSingleVehicle(const YamlMap& root, Scenario* s) {
  const std::string file = root.file();
  const std::string vehicle_path = root.KeyPath("vehicles") + ".0";
  const VehicleSpec& vehicle = s->team.vehicles.front();
  const char* why =
      "; one vehicle carries the payload as a point mass on its cable (the single "
      "vehicle's model, N = 1)";
  if (!vehicle.p_PA_P_m.isZero(0.0)) {
    throw InputError(file, vehicle_path + ".attach_m",
                     std::string("must be [0, 0, 0] or left out") + why);
  }
  if (vehicle.start_slack_m != 0.0) {
    throw InputError(file, vehicle_path + ".start_slack_m",
                     std::string("must be 0 or left out: one vehicle starts at rest on its taut "
                                 "cable") +
                         why);
  }
  YAML::Node params =
      root.Has("params") ? YAML::Clone(root.Node("params")) : YAML::Node(YAML::NodeType::Map);
  // a value of the vehicle list into the params block, unless that block sets it otherwise
  const auto into_params = [&](const std::string& key_path, double Params::*member, const char* key,
                               double value) {
    const std::string section = ParamSection(member);
    const YAML::Node given = params[section][key];
    if (given && given.IsScalar() && given.as<double>() != value) {
      throw InputError(file, key_path,
                       "says " + given.as<std::string>() + " where params." + section + "." + key +
                           " says otherwise; give it once");
    }
    params[section][key] = value;
  };
  if (root.Node("vehicles")[0]["cable_length_m"]) {
    into_params(vehicle_path + ".cable_length_m", &Params::cable_length_m,
                FindParamDecl(ParamsTables(), &Params::cable_length_m).key.c_str(),
                vehicle.cable_length_m);
  }
  if (root.Has("payload")) {
    const YAML::Node payload = root.Node("payload");
    const std::string path = root.KeyPath("payload");
    for (const char* key : {"inertia_kgm2", "on_ground"}) {
      if (payload[key] && !(std::string(key) == "on_ground" && !s->team.payload_on_ground)) {
        throw InputError(
            file, path + "." + key,
            std::string("belongs to a team's rigid payload (two vehicles or more)") + why);
      }
    }
    if (payload["mass_kg"]) {
      into_params(path + ".mass_kg", &Params::payload_mass_kg,
                  FindParamDecl(ParamsTables(), &Params::payload_mass_kg).key.c_str(),
                  s->team.payload_mass_kg);
    }
  }
  if (params.size() > 0) {
    ParamsWithOverrides(Params(), params, file);
    s->params_yaml = YAML::Dump(params);
  }
  s->team = TeamSpec();
}

// Refuses the keys a team scenario would fly without them changing anything: what the single
// vehicle's payload camera and estimator read (a team vehicle flies on motion capture or on its
// own IMU and VIO filter, the payload on motion capture), and the params a team gives per
// vehicle and payload.
void CheckTeamKeys(const YamlMap& root, bool cameras) {
  const auto refuse_keys = [&](const char* block, const std::vector<std::string>& kept,
                               const std::string& why) {
    if (!root.Has(block)) return;
    for (const auto& entry : root.Node(block)) {
      const std::string key = entry.first.as<std::string>();
      if (std::find(kept.begin(), kept.end(), key) != kept.end()) continue;
      throw InputError(root.file(), root.KeyPath(block) + "." + key, why);
    }
  };
  refuse_keys("estimation",
              {"ground_truth", "vehicle_state", "camera", "camera_latency", "detector_noise_scale"},
              "a team's payload is seen by the motion-capture system and, with `camera`, by each "
              "vehicle's payload camera, with no payload estimator: of the estimation block a "
              "team takes ground_truth, vehicle_state, camera, camera_latency and "
              "detector_noise_scale only");
  std::vector<std::string> world_keys = {"profile",   "rate_loop", "latency", "imu",
                                         "vio",       "rate_gyro", "aero",    "wind",
                                         "actuation", "mismatch"};
  if (cameras) world_keys.push_back("camera");  // its payload cameras' image model
  refuse_keys("world", world_keys,
              "a team flies the profile's parts on every vehicle (docs/cooperative.md) but not "
              "the single vehicle's contacts (a team vehicle touching anything is a crash), nor "
              "the camera part without payload cameras (estimation.camera); the payload's mass "
              "is payload.mass_kg, each cable's length its vehicle's cable_length_m");
  if (!root.Has("params")) return;
  const YAML::Node params = root.Node("params");
  const auto refuse_param = [&](double Params::*member, const std::string& where) {
    const std::string section = ParamSection(member);
    const std::string& key = FindParamDecl(ParamsTables(), member).key;
    if (params[section] && params[section].IsMap() && params[section][key]) {
      throw InputError(root.file(), root.KeyPath("params") + "." + section + "." + key,
                       "a team does not fly it: its value is " + where);
    }
  };
  refuse_param(&Params::cable_length_m, "each vehicle's vehicles.I.cable_length_m");
  refuse_param(&Params::payload_mass_kg, "the payload block's payload.mass_kg");
}

// What a team scenario can say and a single-vehicle one cannot, and the other way round: a team
// flies its world profile's parts on every vehicle, its vehicles on motion capture or their
// onboard filters, and takes pushes and faults on the payload or a vehicle named by `vehicle`;
// one vehicle is vehicle 0 and flies on its onboard estimator.
void CheckTeamScenario(const YamlMap& root, const Scenario& s) {
  const int vehicles = static_cast<int>(s.team.vehicles.size());
  if (root.Has("estimation") && root.Map("estimation").Has("vehicle_state")) {
    const std::string key = root.KeyPath("estimation") + ".vehicle_state";
    if (!s.team.IsTeam() && s.estimation.vehicle_state != "onboard") {
      throw InputError(root.file(), key,
                       "a single vehicle flies on its onboard estimator (or the truth with "
                       "ground_truth: true); motion_capture is a team vehicle's");
    }
    if (s.estimation.ground_truth && s.estimation.vehicle_state == "onboard") {
      throw InputError(root.file(), key,
                       "onboard and ground_truth: true contradict each other (the truth replaces "
                       "every estimate)");
    }
  }
  if (s.team.IsTeam()) CheckTeamKeys(root, s.team.payload_cameras);
  CheckEventVehicles(s.events, vehicles,
                     !s.estimation.ground_truth && s.estimation.vehicle_state == "onboard", root);
  // bounds on what this kind of run measures: a team's keys need a team, and a team does not
  // measure the single vehicle's quadrotor, estimator, camera or contact metrics
  for (const ExpectKey& k : ExpectKeys()) {
    if (!s.expect.Has(k.key)) continue;
    const std::string path = root.KeyPath("expect") + "." + k.key;
    if (!s.team.IsTeam() && k.metric.rfind("team.", 0) == 0) {
      throw InputError(
          root.file(), path,
          "bounds a team's metric (" + k.metric + "); this scenario flies one vehicle");
    }
    const bool onboard = !s.estimation.ground_truth && s.estimation.vehicle_state == "onboard";
    if (s.team.IsTeam() && !TeamMeasures(k.metric, onboard, s.team.payload_cameras)) {
      throw InputError(root.file(), path,
                       "bounds " + k.metric +
                           ", which a team run does not measure (the single "
                           "vehicle's quadrotor, estimator, camera and contact metrics)");
    }
  }
}

}  // namespace

// A scenario name becomes out/<name>: no separators, no leading dot, nothing a shell mangles.
bool IsSafeName(const std::string& name) {
  if (name.empty() || name.size() > 64 || name[0] == '.') return false;
  for (char c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-' && c != '.') {
      return false;
    }
  }
  return true;
}

// Where a team vehicle's own state comes from (EstimationSpec::vehicle_state).
const std::vector<std::string>& VehicleStateNames() {
  static const std::vector<std::string> names = {"motion_capture", "onboard"};
  return names;
}

const std::vector<std::string>& CameraNames() {
  static const std::vector<std::string> names = {"render", "analytic"};
  return names;
}

// The world's realism profile (flight unless the scenario says), then its single-number
// overrides and the explicit world-only parameters, and the params block.
void ParseWorld(const YamlMap& root, Scenario* scenario) {
  Scenario& s = *scenario;
  WorldProfileSpec profile = LoadWorldProfile("flight");
  if (root.Has("world")) {
    const YamlMap w = root.Map("world");
    profile = LoadWorldProfile(w.Choice("profile", WorldProfileNames(), "flight"));
    ReadWorldProfileSections(w, &profile);
    // each override within the range params.yaml declares for the field it replaces
    const auto world_override = [&](const char* key, double Params::*member) {
      const ParamDecl<Params>& d = FindParamDecl(ParamsTables(), member);
      return w.Number(key, d.min, d.max);
    };
    if (w.Has("payload_mass")) {
      s.world_payload_mass_kg = world_override("payload_mass", &Params::payload_mass_kg);
    }
    if (w.Has("cable_length")) {
      s.world_cable_length_m = world_override("cable_length", &Params::cable_length_m);
    }
    w.RejectUnknownKeys();
  }
  s.world = profile.world;
  if (root.Has("params")) {
    // checked now against the defaults, applied to the run's params.yaml when it runs
    const YAML::Node block = root.Node("params");
    ParamsWithOverrides(Params(), block, root.file());
    s.params_yaml = YAML::Dump(block);
  }
  s.rate_loop = profile.rate_loop;
}

// The estimation block: what the flight code estimates from and how.
void ParseEstimation(const YamlMap& e, Scenario* scenario) {
  Scenario& s = *scenario;
  s.estimation.camera = e.Choice("camera", CameraNames(), "render");
  s.estimation.ground_truth = e.Bool("ground_truth", false);
  // the estimator keeps 0.5 s of history to apply late detections at their capture time
  s.estimation.camera_latency_s = e.Number("camera_latency", 0.0, 0.4, 0.03);
  s.estimation.detector_noise_scale = e.Number("detector_noise_scale", 0.0, 100.0, 1.0);
  s.estimation.slack_tension_cue = e.Bool("slack_tension_cue", true);
  s.estimation.camera_randomize = e.Bool("camera_randomize", false);
  if (e.Has("estimator")) s.estimation.estimator = e.Choice("estimator", EstimatorNames(), "");
  s.estimation.vehicle_state = e.Choice("vehicle_state", VehicleStateNames(), "motion_capture");
  s.team.payload_cameras = s.team.IsTeam() && e.Has("camera");
  e.RejectUnknownKeys();
}

// The events list, each event before the scenario's end.
void ParseEvents(const YamlMap& root, Scenario* scenario) {
  Scenario& s = *scenario;
  const YAML::Node list = root.Node("events");
  if (!list.IsSequence()) root.Fail("events", "expected a list of events");
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string path = root.KeyPath("events") + "." + std::to_string(i);
    if (!list[i].IsMap()) throw InputError(root.file(), path, "expected an event map");
    s.events.push_back(ParseEvent(YamlMap(list[i], root.file(), path)));
    if (s.events.back().at_s > s.duration_s) {
      throw InputError(root.file(), path + ".at", "event after the end of the scenario");
    }
  }
}

Scenario ParseScenario(const YamlMap& root, const std::optional<std::string>& reference_csv_text) {
  Scenario s;
  s.file = root.file();
  s.name = root.String("name");
  if (!IsSafeName(s.name)) {
    root.Fail("name", "'" + s.name +
                          "' is not a safe folder name: 1 to 64 of A-Z a-z 0-9 _ - ., "
                          "not starting with '.' (it names the default output folder)");
  }
  s.duration_s = root.Number("duration", 1e-3, kMaxScenarioDuration_s);
  s.seed = static_cast<unsigned long>(root.Integer("seed", 0, 4294967295L, 1));

  ParseWorld(root, &s);
  if (root.Has("vehicles")) {
    s.team = ParseTeam(root);
    if (s.team.vehicles.size() == 1) {
      AsSingleVehicle(root, &s);
    } else {
      s.controller.type = TeamControllerNames().front();
    }
  } else if (root.Has("payload")) {
    root.Fail("payload", "a payload block belongs to a team scenario: add a vehicles list");
  }
  if (root.Has("controller")) {
    const YamlMap c = root.Map("controller");
    if (s.team.IsTeam()) {
      // a team's vehicles each fly one of the team controllers, which take no settings
      s.controller.type = c.Choice("type", TeamControllerNames(), s.controller.type);
    } else {
      s.controller.type = c.Choice("type", ControllerNames(), s.controller.type);
      s.controller.settings = ReadControllerSettings(c, s.controller.type);
    }
    c.RejectUnknownKeys();
  }
  if (root.Has("estimation")) ParseEstimation(root.Map("estimation"), &s);
  if (root.Has("reference")) {
    s.reference = ParseReferenceBlock(root.Map("reference"), reference_csv_text);
  }
  if (root.Has("events")) ParseEvents(root, &s);
  if (root.Has("expect")) s.expect = ParseExpect(root.Map("expect"));
  root.RejectUnknownKeys();
  CheckTeamScenario(root, s);
  return s;
}

std::string EstimatorOf(const Scenario& scenario) {
  if (scenario.estimation.estimator) return *scenario.estimation.estimator;
  const ControllerRegistration* controller = FindController(scenario.controller.type);
  return controller != nullptr ? controller->estimator : "hybrid";
}

void CheckControllerType(const std::string& type, const std::string& file, const std::string& key,
                         bool team) {
  const std::vector<std::string>& known = team ? TeamControllerNames() : ControllerNames();
  if (std::find(known.begin(), known.end(), type) != known.end()) return;
  std::string names;
  for (const std::string& name : known) names += (names.empty() ? "" : " | ") + name;
  throw InputError(file, key, "unknown controller '" + type + "', expected one of: " + names);
}

Scenario LoadScenario(const std::string& path, const std::vector<ScenarioSet>& sets,
                      const std::string& origin) {
  return LoadScenarioText(ReadYamlFile(path), path, sets, origin);
}

Scenario LoadScenarioText(const std::string& text, const std::string& path,
                          const std::vector<ScenarioSet>& sets, const std::string& origin,
                          const std::optional<std::string>& reference_csv_text) {
  YAML::Node root = LoadYamlText(text, path);
  if (!root.IsMap()) throw InputError(path, "", "expected a YAML map at the top level");
  if (sets.empty()) return ParseScenario(YamlMap(root, path, ""), reference_csv_text);
  // each set's path as set (an appended entry's own: events+ sets events.2)
  std::vector<std::string> set_paths;
  for (const ScenarioSet& set : sets) {
    set_paths.push_back(SetDottedPath(root, set.first, set.second, origin));
  }
  // a bad value names the set it came from: `--set KEY=VALUE`, or the sweep file with the value
  const auto source = [&](const ScenarioSet& set) {
    return origin == "--set" ? "--set " + set.first + "=" + set.second
                             : origin + " (" + set.first + " = " + set.second + ")";
  };
  try {
    return ParseScenario(YamlMap(root, path, ""), reference_csv_text);
  } catch (const InputError& e) {
    // a bad value that came from a set: name where it came from, not the file it is not in
    for (size_t i = sets.size(); i-- > 0;) {
      const std::string& key = set_paths[i];
      if (e.key() == key || e.key().rfind(key + ".", 0) == 0 || key.rfind(e.key() + ".", 0) == 0) {
        throw InputError(source(sets[i]), e.key(), e.detail());
      }
    }
    throw;
  }
}

ScenarioSet ParseSetArgument(const std::string& text) {
  const size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw InputError("", "--set", "expected PATH=VALUE, got '" + text + "'");
  }
  return {text.substr(0, eq), text.substr(eq + 1)};
}

Params ScenarioParams(const Scenario& scenario, const Params& params) {
  if (scenario.params_yaml.empty()) return params;
  return ParamsWithOverrides(params, YAML::Load(scenario.params_yaml), scenario.file);
}

std::shared_ptr<Reference> MakeReference(const Scenario& scenario, const Params& params) {
  return MakeReference(scenario.reference, params);
}

}  // namespace hpa
