// `hpa compare`: the scenario flown once per controller and once per separate flight stack, into
// a folder each, then the paired comparison of their runs as a table (DIR/comparison.md) and a
// plot.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "hpa/controller/controller_registry.h"
#include "hpa/controller/team_controller.h"
#include "hpa/models/input_error.h"
#include "hpa/scenarios/metric_defs.h"
#include "hpa/scenarios/plot_canvas.h"
#include "hpa/scenarios/plots.h"
#include "hpa/scenarios/runner.h"
#include "hpa/scenarios/scenario.h"
#include "hpa/scenarios/video_recorder.h"
#include "harness/cli/src/cli_parse.h"
#include "harness/cli/src/scenario_command_common.h"
#include "harness/cli/src/scenario_commands.h"

namespace hpa {
namespace {

// Removes what a previous comparison left in `dir` (the table, the plot, and the run outputs of
// each registered controller and of each of this comparison's names), so a killed comparison
// never mixes old and new results.
void RemoveStaleComparison(const std::string& dir, const std::vector<std::string>& names) {
  std::remove((dir + "/comparison.md").c_str());
  for (const std::string& file : PlotFiles(dir + "/comparison")) std::remove(file.c_str());
  std::vector<std::string> folders = ControllerNames();
  folders.insert(folders.end(), names.begin(), names.end());
  for (const std::string& folder : folders) {
    RemoveStaleOutputs(dir + "/" + folder);
    std::remove((dir + "/" + folder + "/slack_events.mp4").c_str());
  }
}

// One entry of `hpa compare`: a registered controller flown in process, or a separate flight
// stack given as --flight-stack NAME=CMD.
struct CompareEntry {
  std::string name;          // its folder DIR/<name>/, its column and its legend label
  std::string flight_stack;  // the shell command of a separate stack ("": a controller type)
};

// The entries of `hpa compare`: the --controllers types, then each --flight-stack NAME=CMD, every
// one checked before the first run (a NAME is a safe folder name, no registered controller's
// and no other entry's; a CMD is a command FlightStackCommandError accepts).
std::vector<CompareEntry> CompareEntries(std::string list, const std::vector<std::string>& stacks,
                                         bool team) {
  std::vector<CompareEntry> entries;
  list += ",";
  for (size_t p = 0; (p = list.find(',')) != std::string::npos; list.erase(0, p + 1)) {
    if (p > 0) entries.push_back({list.substr(0, p), ""});
  }
  if (entries.empty()) throw InputError("", "--controllers", "expected a list such as A,B");
  for (const CompareEntry& e : entries) CheckControllerType(e.name, "", "--controllers", team);
  const std::vector<std::string> registered = team ? TeamControllerNames() : ControllerNames();
  for (const std::string& text : stacks) {
    const size_t eq = text.find('=');
    const std::string name = text.substr(0, eq);
    const auto fail = [&](const std::string& why) {
      throw InputError("", "--flight-stack", "'" + text + "': " + why);
    };
    if (eq == std::string::npos || eq == 0) fail("expected NAME=CMD, e.g. pd=\"python3 pd.py\"");
    if (!IsSafeName(name)) {
      fail("NAME '" + name +
           "' is not a safe folder name: 1 to 64 of A-Z a-z 0-9 _ - ., not "
           "starting with '.' (it names the folder DIR/NAME/)");
    }
    if (std::find(registered.begin(), registered.end(), name) != registered.end()) {
      fail("NAME '" + name + "' is a registered controller's: name the stack otherwise");
    }
    for (const CompareEntry& e : entries) {
      if (e.name == name) fail("NAME '" + name + "' is given twice");
    }
    const std::string why = FlightStackCommandError(text.substr(eq + 1));
    if (!why.empty()) fail(why);
    entries.push_back({name, text.substr(eq + 1)});
  }
  return entries;
}

// The paired comparison of one scenario's runs (same seed): what flew each column, then each
// one's metrics and, for every column after the first, its difference to the first.
std::string ComparisonTable(const std::vector<RunResult>& results,
                            const std::vector<CompareEntry>& entries) {
  std::vector<std::string> types;
  std::string flown;
  for (size_t i = 0; i < results.size(); ++i) {
    types.push_back(entries[i].name);
    if (entries[i].flight_stack.empty()) continue;
    flown += "- " + entries[i].name + ": the flight stack `" + entries[i].flight_stack +
             "`, which flew as " + results[i].metrics.controller + " (flight_stack " +
             results[i].metrics.flight_stack + ")\n";
  }
  // a run that ended in a run error, with its verdict's first cause ("never flew: ...")
  for (size_t i = 0; i < results.size(); ++i) {
    const Metrics& m = results[i].metrics;
    if (!m.run_error || m.expect_failed.empty()) continue;
    flown += "- " + entries[i].name + ": expect failed, " + m.expect_failed.front() + "\n";
  }
  // the rows: every metric of the metric table with a label that this kind of run measures (a
  // team's metrics for a team, none of what a team does not measure), read from each run's
  // metrics.json
  const bool team = results.front().metrics.team.has_value();
  const bool onboard = team && results.front().metrics.team->onboard;
  std::vector<const MetricDef*> rows;
  for (const MetricDef& def : MetricDefs()) {
    if (def.label.empty()) continue;
    const bool team_metric = def.json_path.rfind("team.", 0) == 0;
    if (team ? !TeamMeasures(def.json_path, onboard) : team_metric) continue;
    rows.push_back(&def);
  }
  std::vector<nlohmann::json> metrics;
  for (const RunResult& r : results)
    metrics.push_back(nlohmann::json::parse(MetricsToJson(r.metrics)));
  const auto cell = [](std::optional<double> v) {
    if (!v || !std::isfinite(*v)) return std::string("-");
    char text[32];
    std::snprintf(text, sizeof(text), "%.4g", *v);
    return std::string(text);
  };
  std::string md = flown.empty() ? "" : flown + "\n";
  md += "| metric (seed " + std::to_string(results.front().metrics.seed) + ") |";
  for (const std::string& t : types) md += " " + t + " |";
  for (size_t i = 1; i < types.size(); ++i) md += " " + types[i] + " - " + types[0] + " |";
  md += "\n|---|";
  for (size_t i = 0; i < 2 * types.size() - 1; ++i) md += "---|";
  md += "\n";
  for (const MetricDef* row : rows) {
    md += "| " + row->label + " |";
    for (const nlohmann::json& m : metrics) md += " " + cell(ReadMetric(*row, m)) + " |";
    const std::optional<double> first = ReadMetric(*row, metrics.front());
    for (size_t i = 1; i < metrics.size(); ++i) {
      const std::optional<double> v = ReadMetric(*row, metrics[i]);
      md += " " + cell(v && first ? std::optional<double>(*v - *first) : std::nullopt) + " |";
    }
    md += "\n";
  }
  return md;
}

// What `hpa compare` is asked besides the options every scenario command takes.
struct CompareArgs {
  std::string out_dir, list, plot_format = "png";
  std::vector<std::string> stacks;  // --flight-stack NAME=CMD, in order
  double flight_timeout_s = 10.0;
  bool slack_events = false;
  bool no_control_thread = false;
};

// Adds `hpa compare`'s own options to its parser; returns --controllers (its count says whether
// it was given).
CLI::Option* AddCompareOptions(CLI::App& app, CompareArgs* a) {
  app.add_option("--out", a->out_dir, "output folder")->required();
  CLI::Option* controllers_option =
      app.add_option("--controllers", a->list,
                     "comma-separated controller types, flown first (default "
                     "hpa_mpc,nonhybrid_mpc; a team scenario: cooperative,hpa_mpc)");
  app.add_option("--flight-stack", a->stacks,
                 "NAME=CMD (repeatable): also fly the separate flight stack CMD (a shell command, "
                 "as hpa run --flight-stack) into DIR/NAME/, labelled NAME in the table and the "
                 "plot")
      ->allow_extra_args(false);  // one NAME=CMD per --flight-stack
  app.add_option("--flight-timeout", a->flight_timeout_s,
                 "with --flight-stack: seconds to wait for a stack's whole reply to one tick "
                 "before its run stops with a run error, in [0.001, 3600]")
      ->check(FlightTimeoutError);
  app.add_flag("--video-slack-events", a->slack_events, "a slack-event video per run");
  app.add_option("--plot-format", a->plot_format, "png | svg | pdf: the comparison plot's format")
      ->default_str("png");
  app.add_flag("--no-control-thread", a->no_control_thread,
               "compute the controllers' commands on the simulation's thread (the same runs)");
  return controllers_option;
}

// Flies one entry of the comparison into DIR/<its name>/ (its result appended to `results`),
// writes its metrics and log and says how it went; true when its run ended in an internal error.
bool FlyCompareEntry(const ScenarioOptions& o, const CompareArgs& a, const Scenario& base,
                     const Params& params, const CompareEntry& entry,
                     std::vector<RunResult>* results) {
  Scenario s = base;
  if (entry.flight_stack.empty()) s.controller.type = entry.name;
  const std::string dir = a.out_dir + "/" + entry.name;
  MakeOutputDir(dir);
  // what the run is run from, as hpa run keeps it: `hpa replay DIR` renders it later
  WriteRunRecord(dir, RecordOf(o, entry.flight_stack.empty() ? entry.name : "", params));
  RunOptions options;
  options.progress = !o.quiet;
  options.gl_backend = ParseGlOption(o.gl);
  options.control_thread = !a.no_control_thread && ControlThreadPays();
  options.flight_stack = entry.flight_stack;
  options.flight_step_timeout_s = a.flight_timeout_s;
  const std::string video = a.slack_events ? dir + "/slack_events.mp4" : "";
  std::unique_ptr<VideoTickRecorder> recorder;
  if (a.slack_events) {
    recorder = std::make_unique<VideoTickRecorder>(video, ScenarioRates(s).video.rate_hz, true);
    options.recorders.push_back(recorder.get());
  }
  results->push_back(RunScenario(s, params, options));
  if (recorder) recorder->Finish();
  WriteText(dir + "/metrics.json", MetricsToJson(results->back().metrics));
  WriteRunLogCsv(dir + "/log.csv", results->back());
  bool run_error = false;
  if (results->back().metrics.run_error) {
    std::fprintf(stderr, "hpa: internal error during the %s run (its results are written): %s\n",
                 entry.name.c_str(), results->back().metrics.run_error->c_str());
    run_error = true;
  }
  if (!o.quiet) PrintSummary(results->back().metrics, dir);
  ReportVideo(video, o.quiet);
  return run_error;
}

}  // namespace

int CompareMain(int argc, char** argv) {
  ScenarioOptions o;
  CompareArgs a;
  CLI::App app{
      "Runs the scenario once per controller into DIR/<type>/, and once per --flight-stack "
      "NAME=CMD into DIR/NAME/, and writes DIR/comparison.md and DIR/comparison.png (or .svg, "
      ".pdf) with DIR/comparison.csv, its numbers.",
      "hpa compare"};
  AddScenarioOptions(app, &o, true, true);
  const CLI::Option* controllers_option = AddCompareOptions(app, &a);
  if (const auto code = ParseCommandLine(app, argc, argv)) return *code;
  const PlotFormat format = ParsePlotFormat(a.plot_format);
  const Params params = LoadParamsOf(o);
  const Scenario base = LoadScenarioOf(o);
  // every name and command checked before the first run
  if (controllers_option->count() == 0) {
    a.list = base.team.IsTeam() ? "cooperative,hpa_mpc" : "hpa_mpc,nonhybrid_mpc";
  }
  std::vector<CompareEntry> entries = CompareEntries(a.list, a.stacks, base.team.IsTeam());
  std::vector<std::string> names;
  for (const CompareEntry& e : entries) names.push_back(e.name);
  RemoveStaleComparison(a.out_dir, names);
  std::vector<RunResult> results;
  bool all_passed = true;
  bool run_error = false;
  for (const CompareEntry& entry : entries) {
    if (FlyCompareEntry(o, a, base, params, entry, &results)) run_error = true;
    all_passed = all_passed && results.back().metrics.expect_passed;
    if (StopRequested() != 0) break;  // the entries not yet flown are left out
  }
  entries.resize(results.size());
  names.resize(results.size());
  const std::string png = WriteComparisonPlot(results, ScenarioParams(base, params),
                                              a.out_dir + "/comparison", format, names);
  const std::string table = ComparisonTable(results, entries);
  WriteText(a.out_dir + "/comparison.md", table);
  if (!o.quiet) std::printf("\n%s", table.c_str());
  if (!o.quiet) std::printf("comparison plot %s\n", png.c_str());
  if (const int signal = StopRequested(); signal != 0) {
    std::fprintf(stderr, "hpa: stopped by signal %d (%s); the results so far are written\n", signal,
                 strsignal(signal));
    return kExitStoppedBySignal + signal;
  }
  if (run_error) return kExitInternal;
  return all_passed ? kExitOk : kExitExpectFailed;
}

}  // namespace hpa
