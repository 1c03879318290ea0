#include "hpa/scenarios/golden.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "hpa/models/data_dir.h"
#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/scenarios/metrics.h"
#include "hpa/scenarios/provenance.h"
#include "hpa/scenarios/runner.h"
#include "hpa/scenarios/scenario.h"
#include "harness/cli/src/cli_parse.h"
#include "harness/cli/src/scenario_commands.h"

namespace hpa {
namespace {

using Json = nlohmann::json;
namespace fs = std::filesystem;

// the shipped scenarios (of the source tree, or of an installed prefix)
std::string ScenariosDir() { return DataPath("scenarios"); }

// Fields that measure the machine or name the build, not the behaviour.
bool IsMachineKey(const std::string& key) {
  return key == "build" || key == "wall_time_s" || key == "mpc_solve_ms" || key == "render_ms" ||
         key == "detector_ms" || key == "image_model_ms" || key == "solve_ms";
}

Json StripMachineFields(Json metrics) {
  if (metrics.is_array()) {
    for (Json& entry : metrics) entry = StripMachineFields(std::move(entry));
    return metrics;
  }
  if (!metrics.is_object()) return metrics;
  // at any depth: a team's vehicles each have their controller's update time
  for (auto it = metrics.begin(); it != metrics.end();) {
    if (IsMachineKey(it.key())) {
      it = metrics.erase(it);
    } else {
      it.value() = StripMachineFields(std::move(it.value()));
      ++it;
    }
  }
  return metrics;
}

std::string ReadText(const std::string& path, const std::string& what) {
  return ReadInputFile(path, what);
}

// A tolerance entry {"rel": r, "abs": a}, both finite numbers >= 0 (either may be left out).
void CheckTolerance(const Json& entry, const std::string& file, const std::string& key) {
  if (!entry.is_object()) {
    throw InputError(file, key, "expected {\"rel\": number, \"abs\": number}, got " + entry.dump());
  }
  for (const auto& [name, value] : entry.items()) {
    if (name != "rel" && name != "abs") {
      throw InputError(file, key + "." + name, "unknown key; a tolerance has rel and abs");
    }
    if (!value.is_number() || !std::isfinite(value.get<double>()) || value.get<double>() < 0) {
      throw InputError(file, key + "." + name, "expected a number >= 0, got " + value.dump());
    }
  }
}

Json ParseJson(const std::string& text, const std::string& file) {
  try {
    return Json::parse(text);
  } catch (const Json::exception& e) {
    throw InputError(file, "", std::string("invalid JSON: ") + e.what());
  }
}

// Tolerance of a dotted key: the entry for the key without list indices, else the default, else
// none (exact).
std::pair<double, double> ToleranceOf(const Json& tolerances, const std::string& path) {
  std::string key;
  std::stringstream parts(path);
  for (std::string part; std::getline(parts, part, '.');) {
    if (!part.empty() && std::all_of(part.begin(), part.end(), ::isdigit)) continue;
    key += (key.empty() ? "" : ".") + part;
  }
  // a key's own tolerance, else the default one, else none (exact); never a const document's
  // operator[] on a key it lacks, which is undefined
  const Json* entry = nullptr;
  if (tolerances.contains("keys") && tolerances["keys"].contains(key)) {
    entry = &tolerances["keys"][key];
  } else if (tolerances.contains("default")) {
    entry = &tolerances["default"];
  }
  if (entry == nullptr || !entry->is_object()) return {0.0, 0.0};
  return {entry->value("rel", 0.0), entry->value("abs", 0.0)};
}

// A value as the change list prints it: floats with `digits` significant digits.
std::string Text(const Json& v, int digits = 9) {
  std::ostringstream out;
  if (v.is_number_float()) {
    out.precision(digits);
    out << v.get<double>();
  } else {
    out << v.dump();
  }
  return out.str();
}

// "golden -> now" with as many digits as tell the two apart (17 round-trips any double): a change
// in the 12th digit under --exact must not read "0.0347343189 -> 0.0347343189".
std::string ChangeText(const Json& golden, const Json& now) {
  int digits = 9;
  while (digits < 17 && Text(golden, digits) == Text(now, digits)) digits += 4;
  return Text(golden, std::min(digits, 17)) + " -> " + Text(now, std::min(digits, 17));
}

void Compare(const Json& now, const Json& golden, const std::string& path, const Json& tolerances,
             GoldenDiff* diff) {
  if (now.is_object() && golden.is_object()) {
    for (const auto& [key, value] : golden.items()) {
      const std::string sub = path.empty() ? key : path + "." + key;
      if (!now.contains(key)) {
        diff->changes.push_back(sub + ": missing (golden " + Text(value) + ")");
      } else {
        Compare(now[key], value, sub, tolerances, diff);
      }
    }
    for (const auto& [key, value] : now.items()) {
      if (!golden.contains(key)) diff->new_keys.push_back(path.empty() ? key : path + "." + key);
    }
    return;
  }
  if (now.is_array() && golden.is_array() && now.size() == golden.size()) {
    for (size_t i = 0; i < now.size(); ++i) {
      Compare(now[i], golden[i], path + "." + std::to_string(i), tolerances, diff);
    }
    return;
  }
  if (now.is_number_float() || golden.is_number_float()) {
    if (now.is_number() && golden.is_number()) {
      const double a = now.get<double>(), b = golden.get<double>();
      const auto [rel, abs] = ToleranceOf(tolerances, path);
      const double tolerance = abs + rel * std::max(std::fabs(a), std::fabs(b));
      if (std::fabs(a - b) > tolerance) {
        std::ostringstream line;
        line.precision(3);
        line << path << ": " << ChangeText(golden, now) << " (tolerance " << tolerance << ")";
        diff->changes.push_back(line.str());
      }
      return;
    }
  }
  if (now != golden) diff->changes.push_back(path + ": " + ChangeText(golden, now));
}

// The current metrics of one golden scenario: read from `from_dir` or run here.
Json CurrentMetrics(const std::string& name, const GoldenOptions& options, const Params& params) {
  if (!options.from_dir.empty()) {
    std::string flat = name;
    std::replace(flat.begin(), flat.end(), '/', '_');
    const std::string path = options.from_dir + "/" + flat + "/metrics.json";
    Json metrics = ParseJson(ReadText(path, "the metrics of " + name), path);
    if (!metrics.is_object()) {
      throw InputError(path, "",
                       "expected a metrics.json object, got " + std::string(metrics.type_name()));
    }
    return metrics;
  }
  const Scenario scenario = LoadScenario(ScenariosDir() + "/" + name + ".yaml");
  RunOptions run_options;
  // the controller beside the simulation, as `hpa run` flies it (the same metrics either way)
  run_options.control_thread = ControlThreadPays();
  const RunResult result = RunScenario(scenario, params, run_options);
  return Json::parse(MetricsToJson(result.metrics));
}

}  // namespace

std::vector<std::string> GoldenScenarioNames() {
  std::vector<std::string> names;
  for (const std::string sub : {"", "ci/"}) {
    for (const auto& entry : fs::directory_iterator(ScenariosDir() + "/" + sub)) {
      if (entry.path().extension() == ".yaml") names.push_back(sub + entry.path().stem().string());
    }
  }
  std::sort(names.begin(), names.end());
  return names;
}

GoldenDiff CompareWithGolden(const std::string& metrics_json, const std::string& golden_json,
                             const std::string& tolerances_json) {
  GoldenDiff diff;
  Compare(StripMachineFields(Json::parse(metrics_json)),
          StripMachineFields(Json::parse(golden_json)), "", Json::parse(tolerances_json), &diff);
  return diff;
}

namespace {

// Reads the golden file and checks its tolerances and scenario map before anything runs; with
// --update a file without scenarios gets an empty map, so a first update can fill it.
Json LoadGoldenFile(const std::string& path, bool update) {
  Json golden = ParseJson(ReadText(path, "the golden file"), path);
  if (!golden.is_object()) throw InputError(path, "", "expected a JSON object");
  if (!golden.contains("tolerances") || !golden["tolerances"].is_object() ||
      !golden["tolerances"].contains("default")) {
    throw InputError(path, "tolerances.default", "missing: {\"rel\": ..., \"abs\": ...}");
  }
  CheckTolerance(golden["tolerances"]["default"], path, "tolerances.default");
  if (golden["tolerances"].contains("keys")) {
    const Json& keys = golden["tolerances"]["keys"];
    if (!keys.is_object()) {
      throw InputError(path, "tolerances.keys", "expected a map from metric key to tolerance");
    }
    for (const auto& [key, entry] : keys.items()) {
      CheckTolerance(entry, path, "tolerances.keys." + key);
    }
  }
  if (golden["tolerances"].contains("build_sensitive")) {
    const Json& sensitive = golden["tolerances"]["build_sensitive"];
    if (!sensitive.is_object()) {
      throw InputError(path, "tolerances.build_sensitive",
                       "expected a map from scenario name to the reason it differs between builds");
    }
    for (const auto& [name, reason] : sensitive.items()) {
      if (!reason.is_string()) {
        throw InputError(path, "tolerances.build_sensitive." + name, "expected the reason (text)");
      }
    }
  }
  if (!golden.contains("scenarios")) {
    if (!update) {
      throw InputError(path, "scenarios",
                       "missing: the map of scenario name to metrics (hpa golden --update "
                       "--reason \"...\" writes it)");
    }
    golden["scenarios"] = Json::object();
  }
  if (!golden["scenarios"].is_object()) {
    throw InputError(path, "scenarios",
                     std::string("expected a map of scenario name to metrics, got a JSON ") +
                         golden["scenarios"].type_name());
  }
  return golden;
}

// Refuses what cannot be meant: an update without a reason, --exact with --update.
void CheckGoldenOptions(const GoldenOptions& options) {
  const bool blank_reason = options.reason.find_first_not_of(" \t\r\n") == std::string::npos;
  if (options.update && blank_reason) {
    throw InputError("--reason", "", "an update needs a one-line reason (not blank)");
  }
  if (options.exact && options.update) {
    throw InputError("--exact", "", "compares only; --update records values whatever they are");
  }
}

// Refuses to record a run as golden when it was aborted or failed its expect bounds: golden
// holds finished runs that met their bounds.
void CheckRecordable(const std::string& name, const Json& now) {
  const bool aborted = now.contains("run_error") && !now["run_error"].is_null();
  const bool failed =
      now.contains("expect") && now["expect"].is_object() && !now["expect"].value("passed", true);
  if (aborted || failed) {
    throw InputError(
        name, "",
        aborted ? "the run was aborted (" + now["run_error"].dump() + "): not recorded as golden"
                : "the run failed its expect bounds (" +
                      now["expect"].value("failed", Json::array()).dump() +
                      "): not recorded as golden; fix the scenario or its bounds");
  }
}

// What a golden check found, scenario by scenario: each list names its scenarios.
struct GoldenTally {
  std::vector<std::string> changed;       // compared, and beyond tolerance (or not bit for bit)
  std::vector<std::string> not_in_file;   // shipped but missing from the golden file
  std::vector<std::string> not_compared;  // build-sensitive, flown with another compiler
  std::vector<std::string> dropped;       // in the golden file but no longer shipped
};

// Compares one scenario's metrics with its golden copy and prints what changed; a scenario the
// golden file lacks cannot be compared and is named (on stdout, --quiet or not) and counted apart
// (not when updating: the update records it).
void CompareScenario(const std::string& name, const Json& now, const Json& scenarios,
                     const Json& tolerances, const GoldenOptions& options, GoldenTally* tally) {
  if (!scenarios.contains(name)) {
    if (!options.quiet) std::cerr << " not in the golden file\n";
    if (options.update) return;
    std::cout << name << ": not in the golden file, so not compared (a new scenario: "
              << "`hpa golden --update --reason \"...\"` records it)\n";
    tally->not_in_file.push_back(name);
    return;
  }
  GoldenDiff diff;
  Compare(now, scenarios[name], "", tolerances, &diff);
  if (!options.quiet) std::cerr << (diff.changes.empty() ? " unchanged\n" : " CHANGED\n");
  for (const std::string& c : diff.changes) std::cout << name << ": " << c << "\n";
  if (!diff.new_keys.empty() && !options.update) {
    std::cout << name << ": new keys (not in the golden copy): ";
    for (const std::string& k : diff.new_keys) std::cout << k << " ";
    std::cout << "\n";
  }
  if (!diff.changes.empty()) tally->changed.push_back(name);
}

// "a, b, c" of a list of scenario names.
std::string Listed(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& n : names) text += (text.empty() ? "" : ", ") + n;
  return text;
}

// Prints the verdict of a comparison, naming every scenario that changed or could not be
// compared; the exit code: 1 when one changed, is missing from the file or was dropped from the
// shipped set, else 0 (build-sensitive scenarios flown by another compiler are named, not
// failed).
int ReportGolden(const GoldenTally& t, const GoldenOptions& options, size_t scenario_count,
                 const std::string& path) {
  if (!t.not_compared.empty()) {
    std::cout << "golden: " << t.not_compared.size()
              << " build-sensitive scenarios not compared (flown with another compiler than the "
                 "one that recorded them): "
              << Listed(t.not_compared) << "\n";
  }
  const size_t failing = t.changed.size() + t.not_in_file.size() + t.dropped.size();
  if (failing > 0) {
    std::cout << "golden: " << t.changed.size() << " of " << scenario_count
              << " scenarios changed (" << (options.exact ? "not bit for bit" : "beyond tolerance")
              << ")" << (t.changed.empty() ? "" : ": " + Listed(t.changed));
    if (!t.not_in_file.empty()) {
      std::cout << "; " << t.not_in_file.size()
                << " not in the golden file, not compared: " << Listed(t.not_in_file);
    }
    if (!t.dropped.empty()) {
      std::cout << "; " << t.dropped.size()
                << " in the file but no longer shipped: " << Listed(t.dropped);
    }
    std::cout << "; if deliberate, run `hpa golden --update --reason \"...\"` and commit the "
                 "file\n";
    return 1;
  }
  std::cout << "golden: all " << scenario_count - t.not_compared.size() << " scenarios "
            << (options.exact ? "bit for bit" : "within tolerance") << " of " << path << "\n";
  return 0;
}

// Names the golden file's scenarios that are no longer shipped (when not updating, they fail
// the check; an update drops them).
void NameDropped(const Json& scenarios, const Json& updated, const GoldenOptions& options,
                 GoldenTally* tally) {
  for (const auto& [name, value] : scenarios.items()) {
    if (!updated.contains(name)) {
      std::cout << name << ": in the golden file but no longer shipped\n";
      if (!options.update) tally->dropped.push_back(name);
    }
  }
}

// Rewrites the golden file with the current metrics and the reason for the change.
void WriteGolden(const std::string& path, Json golden, const Json& updated,
                 const GoldenOptions& options, size_t scenario_count) {
  golden["scenarios"] = updated;
  golden["reason"] = options.reason;
  // the compiler that recorded it: build-sensitive scenarios are compared only by that compiler
  golden["recorded_with"] = {{"compiler", ThisBuild().compiler},
                             {"build_type", ThisBuild().build_type}};
  // atomically: a full disk or a kill leaves the previous golden file whole
  WriteFileAtomic(path, golden.dump(1) + "\n");
  std::cout << "golden: wrote " << scenario_count << " scenarios to " << path
            << " (commit it with the reason: " << options.reason << ")\n";
}

}  // namespace

int RunGolden(const GoldenOptions& options) {
  const std::string path =
      options.golden_path.empty() ? ScenariosDir() + "/ci/golden.json" : options.golden_path;
  const Json golden = LoadGoldenFile(path, options.update);
  CheckGoldenOptions(options);
  // --exact: the same build reproduces every value bit for bit, so a change that must not
  // change behaviour is checked with no tolerance at all
  const Json tolerances =
      options.exact ? Json{{"default", {{"rel", 0.0}, {"abs", 0.0}}}} : golden["tolerances"];
  const Params params = LoadParams(DefaultParamsPath());
  const std::vector<std::string> names = GoldenScenarioNames();

  GoldenTally tally;
  Json updated = Json::object();
  const std::string recorded_compiler =
      golden.contains("recorded_with") && golden["recorded_with"].is_object()
          ? golden["recorded_with"].value("compiler", "")
          : "";
  const Json sensitive = golden["tolerances"].value("build_sensitive", Json::object());
  for (const std::string& name : names) {
    if (!options.quiet) std::cerr << "golden: " << name << " ..." << std::flush;
    const Json full = CurrentMetrics(name, options, params);
    const Json now = StripMachineFields(full);
    // a build-sensitive scenario (its result differs between compilers, measured) is compared
    // only when the compiler that flew it is the one that recorded it
    const std::string compiler = full.contains("build") && full["build"].is_object()
                                     ? full["build"].value("compiler", "")
                                     : ThisBuild().compiler;
    if (!options.update && sensitive.contains(name) && !recorded_compiler.empty() &&
        compiler != recorded_compiler) {
      if (!options.quiet) std::cerr << " not compared\n";
      std::cout << name << ": not compared: build-sensitive (" << sensitive[name].get<std::string>()
                << "); recorded with " << recorded_compiler << ", flown with " << compiler << "\n";
      tally.not_compared.push_back(name);
      updated[name] = now;
      continue;
    }
    if (const int signal = StopRequested(); signal != 0) {
      // a run cut short by the signal is no measurement: nothing is compared or written
      std::cout << "\ngolden: stopped by signal " << signal << " (" << strsignal(signal) << ") at "
                << name << "; nothing compared or written\n";
      return kExitStoppedBySignal + signal;
    }
    if (options.update) CheckRecordable(name, now);
    updated[name] = now;
    CompareScenario(name, now, golden["scenarios"], tolerances, options, &tally);
  }
  NameDropped(golden["scenarios"], updated, options, &tally);
  if (options.update) {
    WriteGolden(path, golden, updated, options, names.size());
    return 0;
  }
  return ReportGolden(tally, options, names.size(), path);
}

int GoldenMain(int argc, char** argv) {
  GoldenOptions options;
  CLI::App app{
      "Compares the metrics of every shipped scenario (scenarios/*.yaml, scenarios/ci/*.yaml; "
      "own seed and controller) with the committed golden file; exit 1 lists every change "
      "beyond its tolerance. --update rewrites the file (commit it with the reason).",
      "hpa golden"};
  app.add_option("--golden", options.golden_path, "golden file")
      ->default_str("scenarios/ci/golden.json");
  app.add_option("--from", options.from_dir,
                 "read DIR/<name>/metrics.json (e.g. ctest's build/scenario_out) instead of "
                 "running the scenarios");
  app.add_flag("--update", options.update, "rewrite the golden file from the current metrics");
  app.add_option("--reason", options.reason, "one line: why the behaviour changed (--update)");
  app.add_flag("--exact", options.exact,
               "no tolerance: every value bit for bit (a refactor that must not change "
               "behaviour; the same build reproduces every run exactly)");
  app.add_flag("--quiet", options.quiet, "no progress lines");
  if (const auto code = ParseCommandLine(app, argc, argv)) return *code;
  return RunGolden(options);
}

}  // namespace hpa
