#include "hpa/scenarios/run_record.h"

#include <fstream>
#include <nlohmann/json.hpp>

#include "hpa/models/input_error.h"
#include "hpa/models/params_yaml.h"
#include "hpa/models/yaml_reader.h"

namespace hpa {

void WriteRunRecord(const std::string& dir, const RunRecord& r) {
  nlohmann::json sets = nlohmann::json::array();
  for (const ScenarioSet& s : r.sets) sets.push_back({s.first, s.second});
  YAML::Emitter params;
  params << ParamsToYaml(r.params);
  const nlohmann::json j = {{"scenario_file", r.scenario_file},
                            {"scenario_text", r.scenario_text},
                            {"sets", sets},
                            {"seed", r.seed ? nlohmann::json(*r.seed) : nlohmann::json()},
                            {"camera", r.camera},
                            {"controller", r.controller},
                            {"params_yaml", params.c_str()}};
  const std::string path = dir + "/run.json";
  std::ofstream out(path);
  out << j.dump(2) << "\n";
  out.close();
  if (!out) throw OutputError(path, "cannot write");
}

RunRecord ReadRunRecord(const std::string& dir) {
  const std::string path = dir + "/run.json";
  std::ifstream in(path);
  if (!in) {
    throw InputError(path, "",
                     "cannot open it (runs written by hpa run and hpa sweep "
                     "--keep-logs have one)");
  }
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    RunRecord r;
    r.scenario_file = j.at("scenario_file").get<std::string>();
    r.scenario_text = j.at("scenario_text").get<std::string>();
    for (const nlohmann::json& s : j.at("sets")) {
      r.sets.emplace_back(s.at(0).get<std::string>(), s.at(1).get<std::string>());
    }
    if (!j.at("seed").is_null()) r.seed = j.at("seed").get<unsigned long>();
    r.camera = j.at("camera").get<std::string>();
    r.controller = j.at("controller").get<std::string>();
    r.params = ParseParams(
        YamlMap(YAML::Load(j.at("params_yaml").get<std::string>()), path, "params_yaml"));
    return r;
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, "", std::string("malformed: ") + e.what());
  } catch (const YAML::Exception& e) {
    throw InputError(path, "params_yaml", std::string("malformed: ") + e.what());
  }
}

Scenario ScenarioOf(const RunRecord& r) {
  Scenario s = LoadScenarioText(r.scenario_text, r.scenario_file, r.sets, "run.json");
  if (r.seed) s.seed = *r.seed;
  if (!r.camera.empty()) s.estimation.camera = r.camera;
  if (!r.controller.empty()) s.controller.type = r.controller;
  return s;
}

}  // namespace hpa
