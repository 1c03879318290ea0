// `hpa sweep --keep-logs worst:N[:METRIC]`: the log.csv of the N worst runs, by replaying them
// (a run replays exactly: same scenario, seed and values), so a sweep keeps no log it does not
// need and still gives the ones worth reading.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "hpa/models/yaml_reader.h"
#include "hpa/scenarios/golden.h"
#include "hpa/scenarios/metric_defs.h"
#include "hpa/scenarios/run_record.h"
#include "hpa/scenarios/runner.h"
#include "harness/sweeps/src/sweep_internal.h"

namespace hpa::sweep {

KeepLogsSpec ParseKeepLogs(const std::string& text) {
  KeepLogsSpec spec;
  const auto fail = [&](const std::string& what) -> KeepLogsSpec {
    throw InputError("", "--keep-logs", what + ", got '" + text + "'");
  };
  if (text.rfind("worst:", 0) != 0) return fail("expected worst:N or worst:N:METRIC");
  const std::string rest = text.substr(6);
  const size_t colon = rest.find(':');
  const std::string count = rest.substr(0, colon);
  if (count.empty() || count.size() > 4 ||
      count.find_first_not_of("0123456789") != std::string::npos || std::stoi(count) < 1) {
    return fail("expected a whole number of runs from 1 to 9999 after worst:");
  }
  spec.count = std::stoi(count);
  if (colon != std::string::npos) spec.metric = rest.substr(colon + 1);
  const MetricDef* def = FindMetric(spec.metric);
  if (def == nullptr || def->better == Better::kNeither || def->timing) {
    std::string known;
    for (const MetricDef& m : MetricDefs()) {
      if (m.better != Better::kNeither && !m.timing) known += (known.empty() ? "" : ", ") + m.name;
    }
    return fail("unknown or unranked metric '" + spec.metric + "' (one of " + known + ")");
  }
  return spec;
}

void KeepWorstLogs(const SweepSpec& spec, const std::vector<Record>& records,
                   const KeepLogsSpec& keep, const std::string& out_dir, const Params& params,
                   sim::GlBackend gl_backend) {
  const MetricDef& def = GetMetric(keep.metric);
  // finished runs, crashed first, then the metric's worst end first
  struct Ranked {
    const Record* record;
    double value;
  };
  std::vector<Ranked> ranked;
  for (const Record& r : records) {
    if (r.error) continue;
    const nlohmann::json line = nlohmann::json::parse(r.line);
    const double value = ReadMetric(def, line["metrics"]).value_or(std::nan(""));
    ranked.push_back({&r, value});
  }
  const double sign = def.better == Better::kLower ? 1.0 : -1.0;  // larger is worse after this
  std::stable_sort(ranked.begin(), ranked.end(), [&](const Ranked& a, const Ranked& b) {
    if (a.record->crashed != b.record->crashed) return a.record->crashed;
    const double x = std::isfinite(a.value) ? sign * a.value : -HUGE_VAL;
    const double y = std::isfinite(b.value) ? sign * b.value : -HUGE_VAL;
    return x > y;
  });
  if (ranked.size() > static_cast<size_t>(keep.count)) ranked.resize(keep.count);
  const std::vector<SweepRun> runs = ExpandSweep(spec);
  std::printf("keeping the logs of the %zu worst runs by %s (crashes first):\n", ranked.size(),
              keep.metric.c_str());
  for (const Ranked& r : ranked) {
    const auto run = std::find_if(runs.begin(), runs.end(),
                                  [&](const SweepRun& s) { return s.index == r.record->run; });
    if (run == runs.end()) continue;
    RunOptions options;
    options.gl_backend = gl_backend;
    options.flight_stack = FlightStackOf(spec, *run);  // the stack that flew it flies the replay
    options.flight_step_timeout_s = spec.flight_timeout_s;
    const RunResult result = RunScenario(BuildScenario(spec, *run), params, options);
    const std::string dir = out_dir + "/logs/run_" + std::to_string(run->index);
    MakeOutputDir(dir);
    WriteRunLogCsv(dir + "/log.csv", result);
    // what it ran, for hpa replay: the base's snapshot and the run's values and seed
    RunRecord record;
    record.scenario_file = spec.base_path;
    record.scenario_text = spec.base_text.empty() ? ReadYamlFile(spec.base_path) : spec.base_text;
    // the run's values but the stack factor's (no scenario key)
    for (const auto& value : run->values) {
      if (value.first != kStackFactor) record.sets.push_back(value);
    }
    record.seed = run->seed;
    record.params = params;
    WriteRunRecord(dir, record);
    const std::string metrics = MetricsToJson(result.metrics);
    WriteFileAtomic(dir + "/metrics.json", metrics);
    // the replay is the recorded run, bit for bit (timing aside)
    const nlohmann::json recorded = nlohmann::json::parse(r.record->line)["metrics"];
    const bool same =
        CompareWithGolden(metrics, recorded.dump(), R"({"default": {"rel": 0, "abs": 0}})")
            .changes.empty();
    std::printf("  %s/log.csv (%s %.4g%s)%s\n", dir.c_str(), keep.metric.c_str(), r.value,
                r.record->crashed ? ", crashed" : "",
                same ? "" : "  WARNING: the replay's metrics differ from the record");
  }
}

}  // namespace hpa::sweep
