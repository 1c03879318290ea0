// What the commands that run one scenario share (scenario_command_common.h): their options, the
// scenario and parameters they load, and what a run leaves behind. Each command is in a file of
// its own: `hpa run` (run_command.cc), `hpa compare` (compare_command.cc) and `hpa render-frame`
// (render_frame_command.cc).

#include <sys/stat.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/models/yaml_reader.h"
#include "hpa/scenarios/plot_canvas.h"
#include "hpa/scenarios/plots.h"
#include "hpa/scenarios/run_record.h"
#include "hpa/scenarios/scenario.h"
#include "harness/cli/src/cli_parse.h"
#include "harness/cli/src/scenario_command_common.h"

namespace hpa {

// Adds the shared options to a command's parser.
void AddScenarioOptions(CLI::App& app, ScenarioOptions* o, bool with_camera, bool with_quiet) {
  app.add_option("SCENARIO.yaml", o->scenario_file, "the scenario file")->required();
  app.add_option("--params", o->params_file, "parameter file (default models/params.yaml)");
  app.add_option("--set", o->sets,
                 "PATH=VALUE: changes one dotted key of the scenario (repeatable), e.g. "
                 "--set events.1.impulse.2=0.5; PATH+=VALUE appends VALUE to the list at PATH, "
                 "e.g. --set 'events+={at: 2.0, type: impulse, body: payload, impulse: [0, 0, "
                 "0.1]}'")
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
  if (!o.camera.empty() && s.team.IsTeam()) {
    // a team's vehicles carry no payload camera into the run: a camera choice would change nothing
    throw InputError("", "--camera",
                     "a team scenario flies on motion capture, with no payload camera "
                     "(docs/cooperative.md); leave --camera out");
  }
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

}  // namespace hpa
