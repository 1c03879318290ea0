// `hpa run`, `hpa compare` and `hpa render-frame`: the commands that run one scenario.

#include "scenarios/src/tools/scenario_commands.h"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <string>
#include <vector>

#include "hpa/controller/controller_registry.h"
#include "hpa/controller/team_controller.h"
#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/models/yaml_reader.h"
#include "hpa/scenarios/metric_defs.h"
#include "hpa/scenarios/plots.h"
#include "hpa/scenarios/run_record.h"
#include "hpa/scenarios/runner.h"
#include "hpa/scenarios/scenario.h"
#include "hpa/scenarios/video_recorder.h"
#include "hpa/sim/world.h"
#include "scenarios/src/output/media.h"
#include "scenarios/src/tools/cli_parse.h"

namespace hpa {
namespace {

// Options every scenario command shares (run, compare, render-frame).
struct ScenarioOptions {
  std::string scenario_file;
  std::string params_file;
  std::vector<std::string> sets;  // --set PATH=VALUE, in order
  std::optional<unsigned long> seed;
  std::string camera;         // "" keeps the scenario's
  std::string gl = "osmesa";  // --gl: GL back end of the rendered cameras
  bool quiet = false;
};

// Adds the shared options to a command's parser.
void AddScenarioOptions(CLI::App& app, ScenarioOptions* o, bool with_camera, bool with_quiet) {
  app.add_option("SCENARIO.yaml", o->scenario_file, "the scenario file")->required();
  app.add_option("--params", o->params_file, "parameter file (default models/params.yaml)");
  app.add_option("--set", o->sets,
                 "PATH=VALUE: changes one dotted key of the scenario (repeatable), e.g. "
                 "--set events.1.impulse.2=0.5")
      ->allow_extra_args(false);  // one PATH=VALUE per --set: a later positional is not a set
  app.add_option("--seed", o->seed, "scenario seed")->check(CLI::Range(0UL, 4294967295UL));
  if (with_camera) {
    app.add_option("--camera", o->camera, "payload camera")
        ->check(CLI::IsMember({"render", "analytic"}));
  }
  if (with_quiet) app.add_flag("--quiet", o->quiet, "no progress or summary lines");
  AddGlOption(app, &o->gl);
}

// Loads the scenario with --set applied, then --seed and --camera.
Scenario LoadScenarioOf(const ScenarioOptions& o) {
  std::vector<ScenarioSet> sets;
  for (const std::string& text : o.sets) sets.push_back(ParseSetArgument(text));
  Scenario s = LoadScenario(o.scenario_file, sets, "--set");
  if (o.seed) s.seed = *o.seed;
  if (!o.camera.empty()) s.estimation.camera = o.camera;
  return s;
}

// The parameters: --params or models/params.yaml.
Params LoadParamsOf(const ScenarioOptions& o) {
  return LoadParams(o.params_file.empty() ? DefaultParamsPath() : o.params_file);
}

// What `hpa run` was run from, for DIR/run.json (hpa replay rebuilds the run from it).
RunRecord RecordOf(const ScenarioOptions& o, const std::string& controller, const Params& params) {
  RunRecord r;
  r.scenario_file = o.scenario_file;
  r.scenario_text = ReadYamlFile(o.scenario_file);
  for (const std::string& text : o.sets) r.sets.push_back(ParseSetArgument(text));
  r.seed = o.seed;
  r.camera = o.camera;
  r.controller = controller;
  r.params = params;
  return r;
}

// Writes a whole file atomically (WriteFileAtomic): a reader never sees half a file.
void WriteText(const std::string& path, const std::string& text) { WriteFileAtomic(path, text); }

// Removes the outputs a previous run left in `dir`, so a run that is killed leaves nothing
// that looks complete (metrics.json appears last, whole, when the run has finished).
void RemoveStaleOutputs(const std::string& dir) {
  for (const char* name : {"metrics.json", "log.csv", "run.json"}) {
    std::remove((dir + "/" + name).c_str());
  }
  for (const std::string& stem : RunPlotStems()) {
    for (const std::string& file : PlotFiles(dir + "/" + stem)) std::remove(file.c_str());
  }
}

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

// Says where the video went; a slack-events video of a run without slack is not written, and
// that is said even with --quiet (a missing file would otherwise look like a failure).
void ReportVideo(const std::string& video_path, bool quiet) {
  if (video_path.empty()) return;
  struct stat st;
  if (stat(video_path.c_str(), &st) != 0) {
    std::printf("  no slack event in this run: no video written (%s)\n", video_path.c_str());
  } else if (!quiet) {
    std::printf("  video %s\n", video_path.c_str());
  }
}

// The run's summary lines: speed, crash, tracking errors, slack and solver figures, failed
// expect bounds and where the outputs went.
void PrintSummary(const Metrics& m, const std::string& out_dir) {
  std::printf("%s [%s, %s, seed %lu]: %.2f s simulated in %.2f s wall (%.2f sim s per wall s)\n",
              m.scenario.c_str(), m.controller.c_str(), m.camera.c_str(), m.seed, m.sim_time_s,
              m.wall_time_s, m.sim_time_s / std::max(m.wall_time_s, 1e-9));
  if (m.team) {
    // a team: the payload's tracking, then each vehicle's cable and tilt
    std::printf("  crashed %s%s  payload RMSE [%.3f %.3f %.3f] m  vehicles at least %.3f m apart\n",
                m.crashed ? "YES: " : "no", m.crashed ? m.crash_reason->c_str() : "",
                m.payload_rmse_m.x(), m.payload_rmse_m.y(), m.payload_rmse_m.z(),
                m.team->min_vehicle_separation_m);
    for (size_t i = 0; i < m.vehicles.size(); ++i) {
      const VehicleMetrics& v = m.vehicles[i];
      std::printf(
          "  vehicle %zu: slack %.2f s (%d events, %d re-taut), tilt max %.1f deg, "
          "tension max %.2f N, update median %.4f ms, failures %d\n",
          i, v.slack_time_s, v.slack_events, v.retaut_count, v.tilt_max_deg, v.cable_tension_max_N,
          v.solve_ms.median, v.control_failures);
    }
    for (const auto& f : m.expect_failed) std::printf("  EXPECT FAILED %s\n", f.c_str());
    std::printf("  wrote %s/metrics.json, %s/log.csv\n", out_dir.c_str(), out_dir.c_str());
    return;
  }
  std::printf(
      "  crashed %s%s  payload RMSE [%.3f %.3f %.3f] m (estimate vs reference [%.3f %.3f %.3f] m)"
      "  quad dev max %.3f m\n",
      m.crashed ? "YES: " : "no", m.crashed ? m.crash_reason->c_str() : "", m.payload_rmse_m.x(),
      m.payload_rmse_m.y(), m.payload_rmse_m.z(), m.payload_rmse_est_m.x(),
      m.payload_rmse_est_m.y(), m.payload_rmse_est_m.z(), m.quad_position_deviation_max_m);
  std::printf(
      "  slack %.2f s (%d events), mode accuracy %.3f, payload in view %.3f, "
      "solve median %.3f ms, failures %d\n",
      m.slack_time_s, m.slack_events, m.mode_accuracy, m.payload_in_fov_fraction,
      m.mpc_solve_ms.median, m.mpc_failures);
  for (const auto& f : m.expect_failed) std::printf("  EXPECT FAILED %s\n", f.c_str());
  std::printf("  wrote %s/metrics.json, %s/log.csv\n", out_dir.c_str(), out_dir.c_str());
}

// Writes a finished run's log, its metrics and, with --plots, its plots: the log first, the
// metrics last, so that a complete metrics.json means a finished run.
void WriteRunOutputs(const RunResult& result, const Scenario& scenario, const Params& params,
                     const std::string& out_dir, bool plots, PlotFormat format, bool quiet) {
  WriteRunLogCsv(out_dir + "/log.csv", result);
  WriteText(out_dir + "/metrics.json", MetricsToJson(result.metrics));
  if (!plots) return;
  for (const std::string& png :
       WriteRunPlots(result, ScenarioParams(scenario, params), out_dir, format)) {
    if (!quiet) std::printf("  plot %s\n", png.c_str());
  }
}

// The exit code of a finished run, saying why it failed: an internal error, a crash the
// scenario does not expect (no expect block says a crash is fine) or a failed expect bound.
int RunExitCode(const RunResult& result, const Scenario& scenario) {
  if (const int signal = StopRequested(); signal != 0) {
    std::fprintf(stderr, "hpa: stopped by signal %d (%s); the results so far are written\n", signal,
                 strsignal(signal));
    return kExitStoppedBySignal + signal;
  }
  if (result.metrics.run_error) {
    std::fprintf(stderr, "hpa: internal error during the run (results so far are written): %s\n",
                 result.metrics.run_error->c_str());
    return kExitInternal;
  }
  if (result.metrics.crashed && !result.metrics.expect_passed && !scenario.expect.Has("crashed")) {
    std::fprintf(stderr,
                 "hpa: the vehicle crashed (%s at t = %.3f s) and the scenario does not "
                 "expect a crash\n",
                 result.metrics.crash_reason.value_or("").c_str(),
                 result.metrics.crash_time_s.value_or(0.0));
    return kExitExpectFailed;
  }
  return result.metrics.expect_passed ? kExitOk : kExitExpectFailed;
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
  // the rows: every metric of the metric table with a label, read from each run's metrics.json
  std::vector<const MetricDef*> rows;
  for (const MetricDef& def : MetricDefs()) {
    if (!def.label.empty()) rows.push_back(&def);
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

}  // namespace

int RunMain(int argc, char** argv) {
  ScenarioOptions o;
  std::string out_dir, controller, video, flight_stack, plot_format = "png";
  double flight_timeout_s = 10.0;
  bool slack_events = false, plots = false, no_control_thread = false;
  CLI::App app{"Runs one scenario; writes DIR/metrics.json and DIR/log.csv.", "hpa run"};
  AddScenarioOptions(app, &o, true, true);
  app.add_option("--out", out_dir, "output folder (default out/<scenario name>)");
  app.add_option("--controller", controller,
                 "a registered controller (see hpa --help); a team scenario's: a team controller "
                 "(cooperative | hpa_mpc, hpa schema controllers)");
  app.add_option("--video", video,
                 "MP4 of the chase camera with the onboard inset (a team: every vehicle, each "
                 "with its onboard inset)");
  app.add_flag("--video-slack-events", slack_events,
               "keep only a window around each slack event (alone: DIR/slack_events.mp4)");
  app.add_flag("--plots", plots,
               "write plots of the run into DIR (tracking, xy_path, retaut; a team: tracking, "
               "team_cables), each with the CSV of what it draws");
  app.add_option("--plot-format", plot_format, "png | svg | pdf: the plots' format")
      ->default_str("png");
  app.add_option("--flight-stack", flight_stack,
                 "fly a separate flight stack: a shell command (e.g. hpa-flight, or python3 "
                 "examples/python/hover_controller.py) started with HPA_FLIGHT_SOCKET set and "
                 "run in lockstep over docs/protocol.md's protocol (default: in process)")
      ->check([](const std::string& text) {
        // a blank command starts a shell that exits at once: a mistake, not a flight stack
        if (text.find_first_not_of(" \t\n") == std::string::npos) {
          return "expected a shell command, got '" + text +
                 "' (leave --flight-stack out to fly in process)";
        }
        return std::string();
      });
  app.add_option("--flight-timeout", flight_timeout_s,
                 "with --flight-stack: seconds to wait for its whole reply to one tick before "
                 "the run stops with a run error, in [0.001, 3600]")
      ->check([](const std::string& text) {
        // NaN passes a range check (every comparison with it is false): finite and in range
        double s = 0.0;
        if (!CLI::detail::lexical_cast(text, s) || !std::isfinite(s) || s < 0.001 || s > 3600.0) {
          return "expected seconds in [0.001, 3600], got '" + text + "'";
        }
        return std::string();
      });
  app.add_flag("--no-control-thread", no_control_thread,
               "compute the in-process controller's commands on the simulation's thread (the "
               "same run; by default they are computed on a second core while the simulation "
               "steps on, until the command is due)");
  std::string team_stack = "per_vehicle";
  app.add_option("--team-stack", team_stack,
                 "with --flight-stack and a team scenario: per_vehicle starts one stack process "
                 "per vehicle (HPA_VEHICLE set to its index), one starts a single process that "
                 "flies the whole team (docs/protocol.md, Teams)")
      ->check(CLI::IsMember({"per_vehicle", "one"}))
      ->default_str("per_vehicle");
  if (const auto code = ParseCommandLine(app, argc, argv)) return *code;
  const PlotFormat format = ParsePlotFormat(plot_format);
  const Params params = LoadParamsOf(o);
  Scenario scenario = LoadScenarioOf(o);
  if (!controller.empty()) {
    CheckControllerType(controller, "", "--controller", scenario.team.IsTeam());
    scenario.controller.type = controller;
  }
  if (out_dir.empty()) out_dir = "out/" + scenario.name;
  MakeOutputDir(out_dir);
  RemoveStaleOutputs(out_dir);
  WriteRunRecord(out_dir, RecordOf(o, controller, params));

  RunOptions options;
  options.progress = !o.quiet;
  options.gl_backend = ParseGlOption(o.gl);
  options.flight_stack = flight_stack;
  options.flight_step_timeout_s = flight_timeout_s;
  options.team_stack_per_vehicle = team_stack == "per_vehicle";
  options.control_thread = !no_control_thread && ControlThreadPays();
  if (slack_events && video.empty()) video = out_dir + "/slack_events.mp4";
  std::unique_ptr<VideoTickRecorder> recorder;
  if (!video.empty()) {
    CheckVideoPath(video);
    recorder = std::make_unique<VideoTickRecorder>(video, ScenarioRates(scenario).video.rate_hz,
                                                   slack_events);
    options.recorders.push_back(recorder.get());
  }
  const RunResult result = RunScenario(scenario, params, options);
  if (recorder) recorder->Finish();
  WriteRunOutputs(result, scenario, params, out_dir, plots, format, o.quiet);
  if (!o.quiet) PrintSummary(result.metrics, out_dir);
  ReportVideo(video, o.quiet);
  return RunExitCode(result, scenario);
}

int CompareMain(int argc, char** argv) {
  ScenarioOptions o;
  std::string out_dir, list, plot_format = "png";
  std::vector<std::string> stacks;  // --flight-stack NAME=CMD, in order
  double flight_timeout_s = 10.0;
  bool slack_events = false;
  CLI::App app{
      "Runs the scenario once per controller into DIR/<type>/, and once per --flight-stack "
      "NAME=CMD into DIR/NAME/, and writes DIR/comparison.md and DIR/comparison.png (or .svg, "
      ".pdf) with DIR/comparison.csv, its numbers.",
      "hpa compare"};
  AddScenarioOptions(app, &o, true, true);
  app.add_option("--out", out_dir, "output folder")->required();
  CLI::Option* controllers_option =
      app.add_option("--controllers", list,
                     "comma-separated controller types, flown first (default "
                     "hpa_mpc,nonhybrid_mpc; a team scenario: cooperative,hpa_mpc)");
  app.add_option("--flight-stack", stacks,
                 "NAME=CMD (repeatable): also fly the separate flight stack CMD (a shell command, "
                 "as hpa run --flight-stack) into DIR/NAME/, labelled NAME in the table and the "
                 "plot")
      ->allow_extra_args(false);  // one NAME=CMD per --flight-stack
  app.add_option("--flight-timeout", flight_timeout_s,
                 "with --flight-stack: seconds to wait for a stack's whole reply to one tick "
                 "before its run stops with a run error, in [0.001, 3600]")
      ->check(FlightTimeoutError);
  app.add_flag("--video-slack-events", slack_events, "a slack-event video per run");
  app.add_option("--plot-format", plot_format, "png | svg | pdf: the comparison plot's format")
      ->default_str("png");
  bool no_control_thread = false;
  app.add_flag("--no-control-thread", no_control_thread,
               "compute the controllers' commands on the simulation's thread (the same runs)");
  if (const auto code = ParseCommandLine(app, argc, argv)) return *code;
  const PlotFormat format = ParsePlotFormat(plot_format);
  const Params params = LoadParamsOf(o);
  const Scenario base = LoadScenarioOf(o);
  // every name and command checked before the first run
  if (controllers_option->count() == 0) {
    list = base.team.IsTeam() ? "cooperative,hpa_mpc" : "hpa_mpc,nonhybrid_mpc";
  }
  std::vector<CompareEntry> entries = CompareEntries(list, stacks, base.team.IsTeam());
  std::vector<std::string> names;
  for (const CompareEntry& e : entries) names.push_back(e.name);
  RemoveStaleComparison(out_dir, names);
  std::vector<RunResult> results;
  bool all_passed = true;
  bool run_error = false;
  for (const CompareEntry& entry : entries) {
    Scenario s = base;
    if (entry.flight_stack.empty()) s.controller.type = entry.name;
    const std::string dir = out_dir + "/" + entry.name;
    MakeOutputDir(dir);
    // what the run is run from, as hpa run keeps it: `hpa replay DIR` renders it later
    WriteRunRecord(dir, RecordOf(o, entry.flight_stack.empty() ? entry.name : "", params));
    RunOptions options;
    options.progress = !o.quiet;
    options.gl_backend = ParseGlOption(o.gl);
    options.control_thread = !no_control_thread && ControlThreadPays();
    options.flight_stack = entry.flight_stack;
    options.flight_step_timeout_s = flight_timeout_s;
    const std::string video = slack_events ? dir + "/slack_events.mp4" : "";
    std::unique_ptr<VideoTickRecorder> recorder;
    if (slack_events) {
      recorder = std::make_unique<VideoTickRecorder>(video, ScenarioRates(s).video.rate_hz, true);
      options.recorders.push_back(recorder.get());
    }
    results.push_back(RunScenario(s, params, options));
    if (recorder) recorder->Finish();
    WriteText(dir + "/metrics.json", MetricsToJson(results.back().metrics));
    WriteRunLogCsv(dir + "/log.csv", results.back());
    all_passed = all_passed && results.back().metrics.expect_passed;
    if (results.back().metrics.run_error) {
      std::fprintf(stderr, "hpa: internal error during the %s run (its results are written): %s\n",
                   entry.name.c_str(), results.back().metrics.run_error->c_str());
      run_error = true;
    }
    if (!o.quiet) PrintSummary(results.back().metrics, dir);
    ReportVideo(video, o.quiet);
    if (StopRequested() != 0) break;  // the entries not yet flown are left out
  }
  entries.resize(results.size());
  names.resize(results.size());
  const std::string png = WriteComparisonPlot(results, ScenarioParams(base, params),
                                              out_dir + "/comparison", format, names);
  const std::string table = ComparisonTable(results, entries);
  WriteText(out_dir + "/comparison.md", table);
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

int RenderFrameMain(int argc, char** argv) {
  ScenarioOptions o;
  std::string out, controller, camera = "payload", size;
  double at_s = 0.0;
  CLI::App app{
      "Runs the scenario to time T and writes one camera frame (PNG): the onboard payload "
      "camera, or the videos' chase camera.",
      "hpa render-frame"};
  AddScenarioOptions(app, &o, false, false);
  app.add_option("--at", at_s, "time T [s] in [0, duration]")->required();
  app.add_option("--out", out, "FILE.png")->required();
  app.add_option("--controller", controller, "a registered controller (see hpa --help)");
  app.add_option("--camera", camera, "payload (the onboard camera, default) | chase");
  app.add_option("--size", size,
                 "WxH pixels, each side 16-4096 (default: the camera's own size; payload "
                 "1280x720, chase 960x540)");
  if (const auto code = ParseCommandLine(app, argc, argv)) return *code;
  if (out.size() < 5 || out.compare(out.size() - 4, 4, ".png") != 0) {
    throw InputError("", "--out",
                     "the frame is written as PNG: give a FILE.png, got '" + out + "'");
  }
  if (camera != "payload" && camera != "chase") {
    throw InputError("", "--camera", "expected payload | chase, got '" + camera + "'");
  }
  const bool chase = camera == "chase";
  // the chase camera's size is the videos'; a side beyond 4096 px is no frame anyone looks at
  constexpr int kMinSide_px = 16, kMaxSide_px = 4096;
  int width_px = chase ? VideoRecorder::kWidthPx : 0;  // 0: the payload camera's own
  int height_px = chase ? VideoRecorder::kHeightPx : 0;
  if (!size.empty()) {
    char tail = 0;
    if (std::sscanf(size.c_str(), "%dx%d%c", &width_px, &height_px, &tail) != 2 ||
        width_px < kMinSide_px || width_px > kMaxSide_px || height_px < kMinSide_px ||
        height_px > kMaxSide_px) {
      throw InputError("", "--size", "expected WxH with each side 16-4096 px, got '" + size + "'");
    }
  }
  const Params params = LoadParamsOf(o);
  Scenario scenario = LoadScenarioOf(o);
  if (!controller.empty()) {
    CheckControllerType(controller, "", "--controller");
    scenario.controller.type = controller;
  }
  if (!std::isfinite(at_s) || at_s < 0 || at_s > scenario.duration_s) {
    throw InputError("", "--at", "expected a time in [0, duration] of the scenario");
  }
  RunOptions options;
  options.stop_at_s = at_s;
  options.gl_backend = ParseGlOption(o.gl);
  bool written = false;
  std::optional<OutputError> write_error;  // the media module could not be loaded
  double frame_time_s = at_s;
  options.at_stop = [&](sim::World& world) {
    frame_time_s = world.time_s();
    cv::Mat frame;
    if (chase) {
      // the offscreen buffer bounds a render (Renderer::RenderChaseCamera: at most 1280x720): a
      // larger frame is scaled up from the largest render of its aspect that fits
      constexpr double kMaxRenderWidth_px = 1280.0, kMaxRenderHeight_px = 720.0;
      const double fit =
          std::min({1.0, kMaxRenderWidth_px / width_px, kMaxRenderHeight_px / height_px});
      frame = world.renderer().RenderChaseCamera(std::max(1, static_cast<int>(width_px * fit)),
                                                 std::max(1, static_cast<int>(height_px * fit)));
    } else {
      frame = world.renderer().RenderPayloadCamera();
    }
    if (width_px > 0 && (frame.cols != width_px || frame.rows != height_px)) {
      cv::Mat scaled;
      cv::resize(frame, scaled, cv::Size(width_px, height_px), 0, 0,
                 frame.cols > width_px ? cv::INTER_AREA : cv::INTER_LINEAR);
      frame = scaled;
    }
    try {
      written = WriteImage(out, frame);  // false for an extension OpenCV cannot encode too
    } catch (const OutputError& e) {
      write_error = e;
    }
  };
  const RunResult result = RunScenario(scenario, params, options);
  if (result.metrics.run_error) {
    std::fprintf(stderr, "hpa: internal error during the run: %s\n",
                 result.metrics.run_error->c_str());
    return kExitInternal;
  }
  if (write_error) throw *write_error;
  if (!written) throw OutputError(out, "the PNG could not be written (does its folder exist?)");
  if (result.metrics.crashed) {
    std::printf("note: the vehicle crashed at t = %.3f s (%s); the frame is from then\n",
                frame_time_s, result.metrics.crash_reason.value_or("").c_str());
  }
  std::printf("wrote %s (%s camera at t = %.3f s)\n", out.c_str(), camera.c_str(), frame_time_s);
  return kExitOk;
}

}  // namespace hpa
