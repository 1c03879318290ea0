#pragma once
// What `hpa run`, `hpa compare` and `hpa render-frame` share (private to harness/cli/src/,
// defined in scenario_commands.cc): the options every scenario command takes and the scenario
// and parameters they load, and what a run leaves behind (its record, its outputs cleared before
// it, its summary lines, where its video went).

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

#include "hpa/models/params.h"
#include "hpa/scenarios/metrics.h"
#include "hpa/scenarios/run_record.h"
#include "hpa/scenarios/scenario.h"

namespace hpa {

/// Options every scenario command shares (run, compare, render-frame).
struct ScenarioOptions {
  std::string scenario_file;
  std::string params_file;
  std::vector<std::string> sets;  // --set PATH=VALUE, in order
  std::optional<unsigned long> seed;
  std::string camera;         // "" keeps the scenario's
  std::string gl = "osmesa";  // --gl: GL back end of the rendered cameras
  bool quiet = false;
};

/// Adds the shared options to a command's parser.
void AddScenarioOptions(CLI::App& app, ScenarioOptions* o, bool with_camera, bool with_quiet);

/// Loads the scenario with --set applied, then --seed and --camera.
Scenario LoadScenarioOf(const ScenarioOptions& o);

/// The parameters: --params or models/params.yaml.
Params LoadParamsOf(const ScenarioOptions& o);

/// What `hpa run` was run from, for DIR/run.json (hpa replay rebuilds the run from it).
RunRecord RecordOf(const ScenarioOptions& o, const std::string& controller, const Params& params);

/// Writes a whole file atomically (WriteFileAtomic): a reader never sees half a file.
void WriteText(const std::string& path, const std::string& text);

/// Removes the outputs a previous run left in `dir`, so a run that is killed leaves nothing
/// that looks complete (metrics.json appears last, whole, when the run has finished).
void RemoveStaleOutputs(const std::string& dir);

/// Says where the video went; a slack-events video of a run without slack is not written, and
/// that is said even with --quiet (a missing file would otherwise look like a failure).
void ReportVideo(const std::string& video_path, bool quiet);

/// The run's summary lines: speed, crash, tracking errors, slack and solver figures, failed
/// expect bounds and where the outputs went.
void PrintSummary(const Metrics& m, const std::string& out_dir);

}  // namespace hpa
