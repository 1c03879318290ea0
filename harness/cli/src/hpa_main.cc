// The `hpa` command line (docs/design.md section 7).

#include <sys/stat.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "hpa/controller/controller_registry.h"
#include "hpa/estimator/estimator_registry.h"
#include "hpa/models/data_dir.h"
#include "hpa/models/input_error.h"
#include "hpa/scenarios/cli.h"
#include "hpa/scenarios/expect_keys.h"
#include "hpa/scenarios/golden.h"
#include "hpa/scenarios/replay.h"
#include "hpa/scenarios/run_record.h"
#include "hpa/scenarios/runner.h"
#include "hpa/scenarios/schema.h"
#include "hpa/scenarios/sweep.h"
#include "hpa/scenarios/sweep_diff.h"
#include "hpa/scenarios/video_recorder.h"
#include "hpa_version.h"
#include "harness/cli/src/cli_parse.h"
#include "harness/cli/src/scenario_commands.h"

namespace hpa {
namespace {

const char* kUsage =
    R"(hpa: software-in-the-loop simulator for HPA-MPC (quadrotor + cable-suspended payload)

usage:
  hpa run SCENARIO.yaml [--out DIR] [--seed N] [--controller TYPE] [--camera render|analytic]
                        [--video FILE.mp4] [--video-slack-events] [--plots] [--quiet]
                        [--gl osmesa|egl] [--params FILE] [--set PATH=VALUE]...
                        [--plot-format png|svg|pdf] [--flight-stack "CMD"] [--flight-timeout S]
                        [--no-control-thread]
      Runs one scenario; writes DIR/metrics.json, DIR/log.csv (one row per control step) and
      DIR/run.json (what it ran), plus plots with --plots (--plot-format png|svg|pdf, each with
      its CSV) and an MP4 with --video (--video-slack-events keeps only
      the slack events; alone it writes DIR/slack_events.mp4). DIR defaults to
      out/<scenario name>.
      TYPE: a registered controller (listed below). --set changes one dotted key of the
      scenario (e.g. --set events.1.impulse.2=0.5, --set params.cable.length_m=0.8); sweeps
      print such replay commands. --flight-stack flies a separate flight stack (hpa-flight, or
      your own, e.g. python3 examples/python/hover_controller.py) in lockstep over
      docs/protocol.md's protocol; --flight-timeout bounds its reply to one tick (default 10 s).
      In process, the controller's command is computed on a second core while the simulation
      steps on until it is due (the same run); --no-control-thread computes it in line.
  hpa compare SCENARIO.yaml --out DIR [--controllers A,B] [--flight-stack NAME=CMD]...
                        [--flight-timeout S] [--camera render|analytic]
                        [--seed N] [--video-slack-events] [--quiet] [--gl osmesa|egl]
                        [--params FILE] [--set PATH=VALUE]... [--no-control-thread]
      Runs the scenario once per controller (default hpa_mpc,nonhybrid_mpc) into DIR/<type>/,
      then once per --flight-stack NAME=CMD (a separate stack, as run --flight-stack) into
      DIR/NAME/, and writes DIR/comparison.png and DIR/comparison.md (each one's metrics and
      their differences to the first); with --video-slack-events, a slack-event video per run.
  hpa render-frame SCENARIO.yaml --at T --out FILE.png [--seed N] [--controller TYPE]
                        [--gl osmesa|egl] [--params FILE] [--set PATH=VALUE]...
      Runs the scenario to time T (s) and writes one 1280x720 onboard payload-camera frame.
      --gl egl renders through EGL (a GPU where there is one) instead of OSMesa.
  hpa sweep SWEEP.yaml --out DIR [--jobs N] [--shard K/N] [--keep-logs worst:N[:METRIC]]
                        [--resume [--retry-errors] [--allow-changed-inputs]] [--gl osmesa|egl]
                        [--flight-stack "CMD"] [--flight-timeout S] [--runs N]
                        [--set PATH=VALUE]...
      Monte Carlo sweep: one JSON line per run in DIR/runs.jsonl, then a summary. --jobs
      defaults to the number of cores; --shard K/N (K = 1..N) runs every N-th run; --resume
      skips recorded runs, --retry-errors runs the recorded errors (killed, timed out) again;
      a resume refuses a sweep or base file changed since, unless --allow-changed-inputs;
      --keep-logs replays the N worst runs and keeps their log.csv in DIR/logs/.
      --flight-stack (or the sweep file's flight_stack:) flies every run with its own process
      of a separate flight stack; a resume or merge refuses another stack, and a vary key
      only the in-process flight code reads (controller.*) is refused with one. Given twice
      or more as NAME=CMD, the stacks are the sweep's grid factor flight_stack (each draw flown
      by each stack; sweep-diff DIR DIR --a-where flight_stack=A --b-where flight_stack=B).
      --runs N replaces the file's runs:, --set PATH=VALUE sets a key of the base scenario
      in every run (as hpa run --set), without copying the sweep file.
  hpa merge DIR... --out DIR
      Joins sweep shards and writes DIR/summary.json, DIR/summary.md and plots.
  hpa sweep-diff A B --out DIR [--a-where KEY=VALUE] [--b-where KEY=VALUE] [--verdict-timing]
      Paired comparison of two sweep outputs: per metric B - A, 95 % interval, p-value and a
      verdict (better / worse / no difference shown / inconclusive when too few pairs could
      show the metric's minimum effect); timing metrics are listed apart and given a verdict
      only with --verdict-timing. Writes DIR/diff.md, diff.json, diff.png.
  hpa replay DIR [-o FILE.mp4] [--rate HZ] [--gl osmesa|egl] [--quiet]
      Renders the chase video (onboard inset, heads-up line) of a finished run from its
      DIR/log.csv and DIR/run.json without running it again (hpa run writes both; so does
      sweep --keep-logs in DIR/logs/run_N); default DIR/replay.mp4.
  hpa golden [--exact] [--update --reason TEXT] [--from DIR] [--golden FILE]
      Compares every shipped scenario's metrics with scenarios/ci/golden.json (exit 1 on a
      change beyond tolerance; --exact: on any change at all; each scenario that changed or
      cannot be compared, e.g. missing from the file, is named); --update rewrites it.
  hpa schema [SECTION] [SCENARIO.yaml]
      Prints as Markdown what the tools accept and measure, from their registries: controllers,
      estimators, solvers, events, expect keys, metrics, world-profile keys with their
      units, ranges and values (all: docs/schema.md), or with
      `rates SCENARIO.yaml` every loop and stream of that scenario with its rate and latency.
  hpa --version              the version, the git commit this binary was built from and the
                             data folder it reads (an installed prefix's share/hpa, or the
                             source tree; $HPA_DATA_DIR overrides)
  hpa --help                 this text; hpa COMMAND --help: the command's options

exit codes: 0 ok and every `expect` bound holds; 1 an expectation failed (or an unexpected
crash); 2 bad input (file, key, value; the message names them); 3 internal error; 4 an output
could not be written (disk full, the file-size limit of ulimit -f, no permission); 130 / 143 a
sweep stopped by SIGINT / SIGTERM.
)";

// The usage text plus the registered controllers and estimator variants (from their registries).
std::string Usage() {
  std::string text = kUsage;
  text += "\ncontrollers (controller.type, --controller):\n";
  for (const ControllerRegistration& c : Controllers()) {
    text += "  " + c.name + std::string(16 - std::min<size_t>(15, c.name.size()), ' ') +
            c.description + " (estimator: " + c.estimator + ")\n";
  }
  text += "estimators (estimation.estimator; default: the controller's):\n";
  for (const EstimatorRegistration& e : Estimators()) {
    text += "  " + e.name + std::string(24 - std::min<size_t>(23, e.name.size()), ' ') +
            e.description + "\n";
  }
  text +=
      "world profiles (world.profile; default flight; any number of one overridable under "
      "world:, e.g. --set world.latency.compute_s=0):\n"
      "  flight   contact, drag and wind, actuation spread and battery sag, latency, drifting "
      "VIO,\n"
      "           IMU and camera noise and blur, PX4's rate loop, model mismatch\n"
      "           (models/profiles/flight.yaml, each number with its source; hpa schema world)\n"
      "  ideal    none of these: controller-only tests (models/profiles/ideal.yaml)\n";
  text += "expect keys (scenario `expect:` block):\n";
  for (const ExpectKey& k : ExpectKeys()) {
    text += "  " + k.key + std::string(30 - std::min<size_t>(29, k.key.size()), ' ') +
            k.comparison + " [" + k.unit + "]: " + k.description + "\n";
  }
  return text;
}

// The entries of an hpa compare output folder (DIR/comparison.md, DIR/NAME/run.json), sorted;
// empty for any other folder.
std::vector<std::string> ComparedRuns(const std::string& dir) {
  std::vector<std::string> runs;
  struct stat st;
  if (stat((dir + "/run.json").c_str(), &st) == 0) return runs;
  if (stat((dir + "/comparison.md").c_str(), &st) != 0) return runs;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    if (entry.is_directory() && std::filesystem::exists(entry.path() / "run.json")) {
      runs.push_back(entry.path().filename().string());
    }
  }
  std::sort(runs.begin(), runs.end());
  return runs;
}

int ReplayOne(const ReplayOptions& options, const std::string& out, bool quiet);

int ReplayMain(int argc, char** argv) {
  ReplayOptions options;
  std::string out, gl = "osmesa";
  bool quiet = false;
  CLI::App app{
      "Renders a run's chase video (onboard inset, heads-up line) from its DIR/log.csv "
      "and DIR/run.json, without running it again: DIR is an hpa run output folder, "
      "a sweep's DIR/logs/run_N (--keep-logs), or an hpa compare output folder (each "
      "controller's run into DIR/NAME/replay.mp4). Writes DIR/replay.mp4 by default.",
      "hpa replay"};
  app.add_option("DIR", options.dir, "the run's folder (log.csv, run.json)")->required();
  app.add_option("-o,--out", out, "the MP4 to write (default DIR/replay.mp4)");
  app.add_option("--rate", options.rate_hz, "video frames per second (default 30, the run's)")
      ->check(CLI::Range(1.0, 1000.0));
  app.add_option("--gl", gl, "osmesa | egl: the GL back end of the cameras");
  app.add_flag("--quiet", quiet, "no progress line");
  if (const auto code = ParseCommandLine(app, argc, argv)) return *code;
  options.gl_backend = ParseGlOption(gl);
  options.progress = !quiet;
  // an hpa compare output: each flown entry's folder (with its run.json), one video each
  const std::vector<std::string> runs = ComparedRuns(options.dir);
  if (!runs.empty()) {
    if (!out.empty())
      throw InputError("", "--out", "one video per run of a comparison: leave it out");
    for (const std::string& run : runs) {
      ReplayOptions one = options;
      one.dir = options.dir + "/" + run;
      const int code = ReplayOne(one, one.dir + "/replay.mp4", quiet);
      if (code != kExitOk) return code;
    }
    return kExitOk;
  }
  if (out.empty()) out = options.dir + "/replay.mp4";
  return ReplayOne(options, out, quiet);
}

// Replays one run folder into `out`; the exit code (128 + signal when stopped).
int ReplayOne(const ReplayOptions& options, const std::string& out, bool quiet) {
  const ReplaySummary replay = ReplayToVideo(options, out);
  if (replay.stop_signal != 0) {
    std::fprintf(stderr, "hpa: replay stopped by signal %d (%s) after %d frames; %s is unchanged\n",
                 replay.stop_signal, strsignal(replay.stop_signal), replay.frames, out.c_str());
    return kExitStoppedBySignal + replay.stop_signal;
  }
  if (!quiet) {
    std::printf("wrote %s (%d frames, %s)\n", out.c_str(), replay.frames, replay.codec.c_str());
  }
  return kExitOk;
}

}  // namespace

int HpaMain(int argc, char** argv) {
  // SIGTERM / SIGINT: a run stops at its next tick and writes its metrics and log so far
  std::signal(SIGTERM, RequestStop);
  std::signal(SIGINT, RequestStop);
  // a file-size limit (ulimit -f) would kill hpa mid-write with SIGXFSZ: ignored, the write
  // fails with EFBIG instead and is reported as a full disk is (exit 4, no partial file kept)
  std::signal(SIGXFSZ, SIG_IGN);
  if (argc >= 2 && !std::strcmp(argv[1], "--version")) {
    std::string data;
    try {
      data = DataDir();
    } catch (const InputError& e) {
      data = std::string("none found: ") + e.what();
    }
    std::printf("hpa %s (commit %s)\ndata: %s\n", HPA_VERSION, HPA_GIT_COMMIT, data.c_str());
    return kExitOk;
  }
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") ||
      !std::strcmp(argv[1], "help")) {
    std::fputs(Usage().c_str(), argc < 2 ? stderr : stdout);
    return argc < 2 ? kExitBadInput : kExitOk;
  }
  const std::string command = argv[1];
  try {
    if (command == "run") return RunMain(argc, argv);
    if (command == "compare") return CompareMain(argc, argv);
    if (command == "render-frame") return RenderFrameMain(argc, argv);
    if (command == "sweep") return SweepMain(argc, argv);
    if (command == "merge") return MergeMain(argc, argv);
    if (command == "golden") return GoldenMain(argc, argv);
    if (command == "sweep-diff") return SweepDiffMain(argc, argv);
    if (command == "schema") return SchemaMain(argc, argv);
    if (command == "replay") return ReplayMain(argc, argv);
    throw InputError("", "", "unknown command '" + command + "' (see hpa --help)");
  } catch (const InputError& e) {
    std::fprintf(stderr, "hpa: error: %s\n", e.what());
    return kExitBadInput;
  } catch (const OutputError& e) {
    std::fprintf(stderr, "hpa: error: %s\n", e.what());
    return kExitCannotWrite;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hpa: internal error: %s\n", e.what());
    return kExitInternal;
  }
}

}  // namespace hpa
