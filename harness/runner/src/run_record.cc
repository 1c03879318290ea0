#include "hpa/scenarios/run_record.h"

#include <filesystem>
#include <nlohmann/json.hpp>

#include "hpa/controller/reference.h"
#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "hpa/models/params_yaml.h"
#include "hpa/models/yaml_reader.h"

namespace hpa {
namespace {

// Largest run.json read: the reference CSV's snapshot escaped (each newline or quote becomes two
// characters, so at most twice the CSV's limit) plus the scenario's text (at most 16 MiB, as
// any YAML file) and the params.
constexpr std::uintmax_t kMaxRunJsonBytes = 2 * kMaxReferenceCsvBytes + (std::uintmax_t{32} << 20);

// Largest seed a scenario takes (docs/design.md section 5).
constexpr unsigned long kMaxSeed = 4294967295UL;

// A string field that may also be null (read as ""); anything else is bad input naming `key`.
std::string OptionalString(const nlohmann::json& j, const std::string& key,
                           const std::string& path) {
  const nlohmann::json& v = j.at(key);
  if (v.is_null()) return "";
  if (!v.is_string()) throw InputError(path, key, "expected a string or null, got " + v.dump());
  return v.get<std::string>();
}

// A string field; anything else is bad input naming `key`.
std::string RequiredString(const nlohmann::json& j, const std::string& key,
                           const std::string& path) {
  const nlohmann::json& v = j.at(key);
  if (!v.is_string()) throw InputError(path, key, "expected a string, got " + v.dump());
  return v.get<std::string>();
}

// Rebuilds the scenario a record read from `path` describes, so that a bad one is refused by
// run.json's key: the scenario's text, its sets, or the reference CSV's snapshot.
void CheckScenarioOf(const RunRecord& r, const std::string& path) {
  try {
    ScenarioOf(r);
  } catch (const InputError& e) {
    const std::string where = e.key().empty() ? "" : e.key() + ": ";
    if (e.file().rfind("run.json", 0) == 0) throw InputError(path, "sets", e.what());
    if (e.file() == r.scenario_file) throw InputError(path, "scenario_text", where + e.detail());
    if (r.reference_csv_text) {
      throw InputError(path, "reference_csv_text",
                       where + e.detail() + " (the snapshot of " + e.file() + ")");
    }
    throw InputError(path, "scenario_text", e.what());
  }
}

}  // namespace

void WriteRunRecord(const std::string& dir, const RunRecord& record) {
  RunRecord r = record;
  // absolute, so that a replay from another working directory finds what it names
  if (!r.scenario_file.empty()) {
    r.scenario_file = std::filesystem::absolute(r.scenario_file).lexically_normal().string();
  }
  // the reference's file (a csv reference's samples) travels with the record: replay needs no
  // file to still be there
  if (!r.reference_csv_text) {
    const Scenario scenario = ScenarioOf(r);
    if (!scenario.reference.file.empty()) {
      r.reference_csv_text =
          ReadInputFile(scenario.reference.file, "a reference CSV", kMaxReferenceCsvBytes);
    }
  }
  nlohmann::json sets = nlohmann::json::array();
  for (const ScenarioSet& s : r.sets) sets.push_back({s.first, s.second});
  YAML::Emitter params;
  params << ParamsToYaml(r.params);
  const nlohmann::json j = {
      {"scenario_file", r.scenario_file},
      {"scenario_text", r.scenario_text},
      {"sets", sets},
      {"seed", r.seed ? nlohmann::json(*r.seed) : nlohmann::json()},
      {"camera", r.camera},
      {"controller", r.controller},
      {"params_yaml", params.c_str()},
      {"reference_csv_text",
       r.reference_csv_text ? nlohmann::json(*r.reference_csv_text) : nlohmann::json()}};
  // bytes that are not UTF-8 (in a comment of the scenario or the CSV) become U+FFFD instead of
  // stopping the run
  WriteFileAtomic(dir + "/run.json",
                  j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
}

RunRecord ReadRunRecord(const std::string& dir) {
  const std::string path = dir + "/run.json";
  std::string text;
  try {
    text = ReadInputFile(path, "a run's run.json", kMaxRunJsonBytes);
  } catch (const InputError& e) {
    throw InputError(path, "",
                     e.detail() + " (runs written by hpa run and hpa sweep --keep-logs have one)");
  }
  RunRecord r;
  try {
    const nlohmann::json j = nlohmann::json::parse(text);
    if (!j.is_object()) throw InputError(path, "", "expected a JSON object");
    r.scenario_file = RequiredString(j, "scenario_file", path);
    r.scenario_text = RequiredString(j, "scenario_text", path);
    const nlohmann::json& sets = j.at("sets");
    if (!sets.is_array()) throw InputError(path, "sets", "expected a list of [path, value] pairs");
    for (size_t i = 0; i < sets.size(); ++i) {
      const nlohmann::json& s = sets[i];
      if (!s.is_array() || s.size() != 2 || !s[0].is_string() || !s[1].is_string()) {
        throw InputError(path, "sets." + std::to_string(i),
                         "expected a [path, value] pair of strings, got " + s.dump());
      }
      r.sets.emplace_back(s[0].get<std::string>(), s[1].get<std::string>());
    }
    const nlohmann::json& seed = j.at("seed");
    if (!seed.is_null()) {
      if (!seed.is_number_unsigned() || seed.get<std::uint64_t>() > kMaxSeed) {
        throw InputError(path, "seed",
                         "expected null or a whole number in [0, 4294967295], got " + seed.dump());
      }
      r.seed = static_cast<unsigned long>(seed.get<std::uint64_t>());
    }
    r.camera = OptionalString(j, "camera", path);
    if (!r.camera.empty()) {
      bool known = false;
      std::string names;
      for (const std::string& name : CameraNames()) {
        known = known || name == r.camera;
        names += (names.empty() ? "" : " | ") + name;
      }
      if (!known) {
        throw InputError(path, "camera",
                         "unknown camera '" + r.camera + "', expected \"\", null or " + names);
      }
    }
    r.controller = OptionalString(j, "controller", path);
    if (!r.controller.empty()) CheckControllerType(r.controller, path, "controller");
    const std::string params_yaml = RequiredString(j, "params_yaml", path);
    YAML::Node params_node;
    try {
      params_node = LoadYamlText(params_yaml, path);
    } catch (const InputError& e) {
      throw InputError(path, "params_yaml", e.detail());
    }
    if (!params_node.IsMap()) throw InputError(path, "params_yaml", "expected a YAML map");
    r.params = ParseParams(YamlMap(params_node, path, "params_yaml"));
    // optional: records written before it was kept have none
    if (j.contains("reference_csv_text") && !j.at("reference_csv_text").is_null()) {
      r.reference_csv_text = RequiredString(j, "reference_csv_text", path);
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, "", std::string("malformed: ") + e.what());
  } catch (const YAML::Exception& e) {
    throw InputError(path, "params_yaml", std::string("malformed: ") + e.what());
  }
  CheckScenarioOf(r, path);
  return r;
}

Scenario ScenarioOf(const RunRecord& r) {
  Scenario s =
      LoadScenarioText(r.scenario_text, r.scenario_file, r.sets, "run.json", r.reference_csv_text);
  if (r.seed) s.seed = *r.seed;
  if (!r.camera.empty()) s.estimation.camera = r.camera;
  if (!r.controller.empty()) s.controller.type = r.controller;
  return s;
}

}  // namespace hpa
