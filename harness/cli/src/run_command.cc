// `hpa run`: one scenario flown into a folder (its log, its metrics and, when asked, its plots
// and a video), its summary lines, and the exit code saying whether it passed.

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "hpa/controller/controller_registry.h"
#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/scenarios/plot_canvas.h"
#include "hpa/scenarios/plots.h"
#include "hpa/scenarios/run_record.h"
#include "hpa/scenarios/runner.h"
#include "hpa/scenarios/scenario.h"
#include "hpa/scenarios/video_recorder.h"
#include "harness/cli/src/cli_parse.h"
#include "harness/cli/src/scenario_command_common.h"
#include "harness/cli/src/scenario_commands.h"

namespace hpa {
namespace {

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

// What `hpa run` is asked besides the options every scenario command takes.
struct RunArgs {
  std::string out_dir, controller, video, flight_stack, plot_format = "png";
  double flight_timeout_s = 10.0;
  bool slack_events = false, plots = false, no_control_thread = false;
  bool overwrite = false;  // replace another scenario's results in --out
  std::string team_stack = "per_vehicle";
};

// Adds `hpa run`'s own options to its parser.
void AddRunOptions(CLI::App& app, RunArgs* a) {
  app.add_option("--out", a->out_dir,
                 "output folder (default out/<scenario name>); one holding another scenario's "
                 "results is refused unless --overwrite");
  app.add_flag("--overwrite", a->overwrite,
               "replace the results of another scenario in --out (a rerun of the same scenario "
               "replaces its own without it)");
  app.add_option("--controller", a->controller,
                 "a registered controller (see hpa --help); a team scenario's: a team controller "
                 "(cooperative | hpa_mpc, hpa schema controllers)");
  app.add_option("--video", a->video,
                 "MP4 of the chase camera with the onboard inset (a team: every vehicle, each "
                 "with its onboard inset)");
  app.add_flag("--video-slack-events", a->slack_events,
               "keep only a window around each slack event (alone: DIR/slack_events.mp4)");
  app.add_flag("--plots", a->plots,
               "write plots of the run into DIR (tracking, xy_path, retaut; a team: tracking, "
               "team_cables), each with the CSV of what it draws");
  app.add_option("--plot-format", a->plot_format, "png | svg | pdf: the plots' format")
      ->default_str("png");
  app.add_option("--flight-stack", a->flight_stack,
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
  app.add_option("--flight-timeout", a->flight_timeout_s,
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
  app.add_flag("--no-control-thread", a->no_control_thread,
               "compute the in-process controller's commands on the simulation's thread (the "
               "same run; by default they are computed on a second core while the simulation "
               "steps on, until the command is due)");
  app.add_option("--team-stack", a->team_stack,
                 "with --flight-stack and a team scenario: per_vehicle starts one stack process "
                 "per vehicle (HPA_VEHICLE set to its index), one starts a single process that "
                 "flies the whole team (docs/protocol.md, Teams)")
      ->check(CLI::IsMember({"per_vehicle", "one"}))
      ->default_str("per_vehicle");
}

// Refuses --team-stack where it would change nothing: on a single-vehicle scenario, and on a
// team flown in process (it chooses how a team's separate flight stacks run).
void CheckTeamStackOption(const CLI::App& app, const Scenario& scenario, const RunArgs& a) {
  if (app.count("--team-stack") == 0) return;
  if (!scenario.team.IsTeam()) {
    throw InputError("", "--team-stack",
                     "this scenario flies one vehicle; --team-stack chooses how a team's separate "
                     "flight stacks run");
  }
  if (a.flight_stack.empty()) {
    throw InputError("", "--team-stack",
                     "only with --flight-stack: a team flown in process starts no stack process");
  }
}

// Refuses to replace another scenario's results: a DIR/metrics.json that is not this scenario's
// (another scenario's name, or not a run's metrics at all) stays unless --overwrite; a rerun of
// the same scenario (any seed, controller or stack) replaces its own.
void CheckOutFolder(const std::string& dir, const std::string& scenario_name, bool overwrite) {
  if (overwrite) return;
  std::ifstream in(dir + "/metrics.json");
  if (!in) return;
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  const bool named = j.is_object() && j.contains("scenario") && j.at("scenario").is_string();
  if (named && j.at("scenario").get<std::string>() == scenario_name) return;
  const std::string held = named ? "the results of scenario '" +
                                       j.at("scenario").get<std::string>() + "'"
                                 : "a metrics.json that is not a run's";
  throw InputError("", "--out",
                   dir + " holds " + held + ", and this run is scenario '" + scenario_name +
                       "': give another --out, or --overwrite to replace them");
}

// The run's options from the command line (a video's recorder is added beside them).
RunOptions RunOptionsOf(const ScenarioOptions& o, const RunArgs& a) {
  RunOptions options;
  options.progress = !o.quiet;
  options.gl_backend = ParseGlOption(o.gl);
  options.flight_stack = a.flight_stack;
  options.flight_step_timeout_s = a.flight_timeout_s;
  options.team_stack_per_vehicle = a.team_stack == "per_vehicle";
  options.control_thread = !a.no_control_thread && ControlThreadPays();
  return options;
}

}  // namespace

int RunMain(int argc, char** argv) {
  ScenarioOptions o;
  RunArgs a;
  CLI::App app{"Runs one scenario; writes DIR/metrics.json and DIR/log.csv.", "hpa run"};
  AddScenarioOptions(app, &o, true, true);
  AddRunOptions(app, &a);
  if (const auto code = ParseCommandLine(app, argc, argv)) return *code;
  const PlotFormat format = ParsePlotFormat(a.plot_format);
  const Params params = LoadParamsOf(o);
  Scenario scenario = LoadScenarioOf(o);
  if (!a.controller.empty()) {
    CheckControllerType(a.controller, "", "--controller", scenario.team.IsTeam());
    scenario.controller.type = a.controller;
  }
  CheckTeamStackOption(app, scenario, a);
  if (a.out_dir.empty()) a.out_dir = "out/" + scenario.name;
  CheckOutFolder(a.out_dir, scenario.name, a.overwrite);
  MakeOutputDir(a.out_dir);
  RemoveStaleOutputs(a.out_dir);
  WriteRunRecord(a.out_dir, RecordOf(o, a.controller, params));

  RunOptions options = RunOptionsOf(o, a);
  if (a.slack_events && a.video.empty()) a.video = a.out_dir + "/slack_events.mp4";
  std::unique_ptr<VideoTickRecorder> recorder;
  if (!a.video.empty()) {
    CheckVideoPath(a.video);
    recorder = std::make_unique<VideoTickRecorder>(a.video, ScenarioRates(scenario).video.rate_hz,
                                                   a.slack_events);
    options.recorders.push_back(recorder.get());
  }
  const RunResult result = RunScenario(scenario, params, options);
  if (recorder) recorder->Finish();
  WriteRunOutputs(result, scenario, params, a.out_dir, a.plots, format, o.quiet);
  if (!o.quiet) PrintSummary(result.metrics, a.out_dir);
  ReportVideo(a.video, o.quiet);
  return RunExitCode(result, scenario);
}

}  // namespace hpa
