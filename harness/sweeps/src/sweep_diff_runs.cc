#include "harness/sweeps/src/sweep_diff_runs.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>

#include "harness/sweeps/src/sweep_diff_basis.h"
#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "hpa/scenarios/provenance.h"

namespace hpa::sweep_diff_runs {
namespace {

using Json = nlohmann::json;

// Whether two varied values are the same: numerically when both are numbers (1 == 1.0 ==
// 1e0), else as exact text.
bool SameValue(const std::string& a, const std::string& b) {
  const auto number = [](const std::string& text) -> std::optional<double> {
    if (text.empty()) return std::nullopt;
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (end != text.c_str() + text.size() || !std::isfinite(v)) return std::nullopt;
    return v;
  };
  const auto x = number(a), y = number(b);
  if (x && y) return *x == *y;
  return a == b;
}

// One line of runs.jsonl as a Run; an InputError naming the line for one that is no run record.
Run ParseRunRecord(const std::string& path, const std::string& line, int number) {
  Json j;
  try {
    j = Json::parse(line);
  } catch (const Json::exception& e) {
    throw InputError(path, "line " + std::to_string(number), e.what());
  }
  // the record's shape, checked before it is read (a hand-edited or foreign file)
  const std::string where = "line " + std::to_string(number);
  if (!j.is_object()) throw InputError(path, where, "expected a JSON object (a run record)");
  if (j.contains("values") && !j["values"].is_object()) {
    throw InputError(path, where + ": values", "expected an object of varied values");
  }
  if (j.contains("metrics") && !j["metrics"].is_object() && !j["metrics"].is_null()) {
    throw InputError(path, where + ": metrics", "expected a metrics.json object or null");
  }
  Run r;
  try {
    r.draw = j.value("draw", 0);
    r.seed = j.value("seed", 0ul);
    r.sweep = j.value("sweep", "");
    r.controller = j.value("controller", "");
    r.inputs_id = j.contains("inputs_id") ? j.value("inputs_id", "") : j.value("sweep_id", "");
    r.build = j.contains("build") ? DescribeBuild(BuildFromJson(j["build"])) : "not recorded";
    for (const auto& [key, value] : j["values"].items()) {
      r.values[key] = value.is_string() ? value.get<std::string>() : value.dump();
    }
    r.ok = j.value("status", "") == "ok";
    r.metrics = j.contains("metrics") ? j["metrics"] : Json();
    r.basis = EstimationBasis(r.metrics);
  } catch (const Json::exception& e) {
    throw InputError(path, where, std::string("malformed run record: ") + e.what());
  }
  return r;
}

// The runs whose varied `filter_key` has `filter_value` (numeric values match numerically); an
// InputError listing the keys or values there are when none has it.
std::vector<Run> FilterRuns(std::vector<Run> runs, const std::string& filter_key,
                            const std::string& filter_value, const std::string& path,
                            const std::string& where) {
  std::vector<Run> kept;
  std::set<std::string> present;
  for (Run& r : runs) {
    const auto it = r.values.find(filter_key);
    if (it == r.values.end()) continue;
    present.insert(it->second);
    if (SameValue(it->second, filter_value)) kept.push_back(std::move(r));
  }
  if (kept.empty()) {
    std::string listed;
    if (present.empty()) {
      std::set<std::string> keys;
      for (const Run& r : runs) {
        for (const auto& [k, v] : r.values) keys.insert(k);
      }
      for (const std::string& k : keys) listed += (listed.empty() ? "" : ", ") + k;
      throw InputError(path, where,
                       "'" + filter_key + "' is not a varied key of this sweep; varied keys: " +
                           (listed.empty() ? "none" : listed));
    }
    for (const std::string& v : present) listed += (listed.empty() ? "" : ", ") + v;
    throw InputError(
        path, where,
        "no run has " + filter_key + " = " + filter_value + "; values present: " + listed);
  }
  return kept;
}

}  // namespace

std::vector<Run> ReadRuns(const std::string& dir, const std::string& where) {
  const std::string path = dir + "/runs.jsonl";
  CheckInputFile(path, "a sweep's runs.jsonl");
  std::ifstream in(path);
  if (!in) throw InputError(path, "", "cannot read (not a sweep output folder?)");
  std::string filter_key, filter_value;
  if (!where.empty()) {
    const size_t eq = where.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw InputError("--a-where/--b-where", "", "expected KEY=VALUE, got '" + where + "'");
    }
    filter_key = where.substr(0, eq);
    filter_value = where.substr(eq + 1);
  }
  std::vector<Run> runs;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.empty()) continue;
    runs.push_back(ParseRunRecord(path, line, number));
  }
  if (runs.empty()) throw InputError(path, "", "no runs recorded");
  if (filter_key.empty()) return runs;
  return FilterRuns(std::move(runs), filter_key, filter_value, path, where);
}

}  // namespace hpa::sweep_diff_runs
