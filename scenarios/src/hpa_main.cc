// The `hpa` command line (DESIGN.md section 6).

#include <sys/stat.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "hpa/controller/controller_registry.h"
#include "hpa/estimator/estimator_registry.h"
#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/models/yaml_reader.h"
#include "hpa/scenarios/cli.h"
#include "hpa/scenarios/expect_keys.h"
#include "hpa/scenarios/golden.h"
#include "hpa/scenarios/plots.h"
#include "hpa/scenarios/runner.h"
#include "hpa/scenarios/sweep.h"
#include "hpa/scenarios/sweep_diff.h"
#include "hpa/sim/world.h"

namespace hpa {
namespace {

constexpr int kExitOk = 0;
constexpr int kExitExpectFailed = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitInternal = 3;

const char* kUsage =
    R"(hpa: software-in-the-loop simulator for HPA-MPC (quadrotor + cable-suspended payload)

usage:
  hpa run SCENARIO.yaml [--out DIR] [--seed N] [--controller TYPE] [--camera render|analytic]
                        [--video FILE.mp4] [--video-slack-events] [--plots] [--quiet]
                        [--params FILE] [--set PATH=VALUE]...
      Runs one scenario; writes DIR/metrics.json and DIR/log.csv (one row per control step),
      plus PNG plots with --plots and an MP4 with --video (--video-slack-events keeps only
      the slack events; alone it writes DIR/slack_events.mp4). DIR defaults to
      out/<scenario name>.
      TYPE: a registered controller (listed below). --set changes one dotted key of the
      scenario (e.g. --set events.1.impulse.2=0.5); sweeps print such replay commands.
  hpa compare SCENARIO.yaml --out DIR [--controllers A,B] [--camera render|analytic]
                        [--seed N] [--video-slack-events] [--quiet] [--params FILE]
      Runs the scenario once per controller (default hpa_mpc,nonhybrid_mpc) into DIR/<type>/
      and writes DIR/comparison.png; with --video-slack-events, a slack-event video per run.
  hpa render-frame SCENARIO.yaml --at T --out FILE.png [--seed N] [--controller TYPE]
                        [--params FILE]
      Runs the scenario to time T (s) and writes one 1280x720 onboard payload-camera frame.
  hpa sweep SWEEP.yaml --out DIR [--jobs N] [--shard K/N] [--resume]
      Monte Carlo sweep: one JSON line per run in DIR/runs.jsonl, then a summary. --jobs
      defaults to the number of cores; --shard K/N (K = 1..N) runs every N-th run.
  hpa merge DIR... --out DIR
      Joins sweep shards and writes DIR/summary.json, DIR/summary.md and plots.
  hpa sweep-diff A B --out DIR [--a-where KEY=VALUE] [--b-where KEY=VALUE]
      Paired comparison of two sweep outputs: per metric B - A, 95 % interval, p-value and a
      verdict (better / worse / same); writes DIR/diff.md, diff.json, diff.png.
  hpa golden [--update --reason TEXT] [--from DIR] [--golden FILE]
      Compares every shipped scenario's metrics with scenarios/ci/golden.json (exit 1 on a
      change beyond tolerance); --update rewrites it.
  hpa --help

exit codes: 0 ok and every `expect` bound holds; 1 an expectation failed (or an unexpected
crash); 2 bad input (file, key, value; the message names them); 3 internal error.
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
  text += "expect keys (scenario `expect:` block):\n";
  for (const ExpectKey& k : ExpectKeys()) {
    text += "  " + k.key + std::string(30 - std::min<size_t>(29, k.key.size()), ' ') +
            k.comparison + " [" + k.unit + "]: " + k.description + "\n";
  }
  return text;
}

// Command-line arguments: positionals and --flags (with or without a value).
struct Args {
  std::vector<std::string> positional;
  std::vector<std::string> sets;  // --set PATH=VALUE, repeatable
  std::map<std::string, std::string> flags;

  bool Has(const std::string& f) const { return flags.count(f) > 0; }
  std::string Get(const std::string& f, const std::string& fallback = "") const {
    auto it = flags.find(f);
    return it == flags.end() ? fallback : it->second;
  }
};

Args Parse(int argc, char** argv, int first, const std::vector<std::string>& valued,
           const std::vector<std::string>& switches) {
  Args a;
  for (int i = first; i < argc; ++i) {
    const std::string s = argv[i];
    if (s.rfind("--", 0) != 0) {
      a.positional.push_back(s);
      continue;
    }
    if (s == "--set" && std::find(valued.begin(), valued.end(), s) != valued.end()) {
      if (i + 1 >= argc) throw InputError("", s, "expects PATH=VALUE");
      a.sets.push_back(argv[++i]);
    } else if (std::find(switches.begin(), switches.end(), s) != switches.end()) {
      a.flags[s] = "1";
    } else if (std::find(valued.begin(), valued.end(), s) != valued.end()) {
      if (i + 1 >= argc) throw InputError("", s, "expects a value");
      a.flags[s] = argv[++i];
    } else {
      throw InputError("", s, "unknown option (see hpa --help)");
    }
  }
  return a;
}

double ParseNumber(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(v)) {
    throw InputError("", flag, "expected a number, got '" + text + "'");
  }
  return v;
}

// Loads a scenario with --set PATH=VALUE applied (the form summary.md's replay commands use).
Scenario LoadWithSets(const std::string& path, const std::vector<std::string>& sets) {
  if (sets.empty()) return LoadScenario(path);
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw InputError(path, "", "cannot open file");
  } catch (const YAML::Exception& e) {
    throw InputError(path, "", std::string("malformed YAML: ") + e.what());
  }
  for (const std::string& set : sets) {
    const size_t eq = set.find('=');
    if (eq == std::string::npos || eq == 0)
      throw InputError("", "--set", "expected PATH=VALUE, got '" + set + "'");
    SetDottedPath(root, set.substr(0, eq), set.substr(eq + 1), "--set");
  }
  return ParseScenario(YamlMap(root, path, ""));
}

// Applies --seed, --controller and --camera to a loaded scenario.
void ApplyOverrides(const Args& a, Scenario* s) {
  if (a.Has("--seed")) {
    const std::string text = a.Get("--seed");
    char* end = nullptr;
    errno = 0;
    const unsigned long long seed = std::strtoull(text.c_str(), &end, 10);
    if (text.empty() || text[0] == '-' || *end != '\0' || errno != 0 || seed > 4294967295ULL) {
      throw InputError("", "--seed", "expected an integer in [0, 4294967295], got '" + text + "'");
    }
    s->seed = static_cast<unsigned long>(seed);
  }
  if (a.Has("--controller")) {
    const std::string c = a.Get("--controller");
    CheckControllerType(c, "", "--controller");
    s->controller.type = c;
  }
  if (a.Has("--camera")) {
    const std::string c = a.Get("--camera");
    if (c != "render" && c != "analytic") {
      throw InputError("", "--camera", "expected render | analytic");
    }
    s->estimation.camera = c;
  }
}

// Writes a whole file; a write that does not reach the file (a full disk) is an error.
void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  if (!out) throw InputError(path, "", "cannot write file");
  out << text;
  out.flush();
  if (!out) throw std::runtime_error("cannot write " + path + " (disk full?)");
}

void PrintSummary(const Metrics& m, const std::string& out_dir) {
  std::printf("%s [%s, %s, seed %lu]: %.2f s simulated in %.2f s wall (%.2f sim s per wall s)\n",
              m.scenario.c_str(), m.controller.c_str(), m.camera.c_str(), m.seed, m.sim_time_s,
              m.wall_time_s, m.sim_time_s / std::max(m.wall_time_s, 1e-9));
  std::printf("  crashed %s%s  payload RMSE [%.3f %.3f %.3f] m  quad dev max %.3f m\n",
              m.crashed ? "YES: " : "no", m.crashed ? m.crash_reason->c_str() : "",
              m.payload_rmse_m.x(), m.payload_rmse_m.y(), m.payload_rmse_m.z(),
              m.quad_position_deviation_max_m);
  std::printf(
      "  slack %.2f s (%d events), mode accuracy %.3f, payload in view %.3f, "
      "solve median %.3f ms, failures %d\n",
      m.slack_time_s, m.slack_events, m.mode_accuracy, m.payload_in_fov_fraction,
      m.mpc_solve_ms.median, m.mpc_failures);
  for (const auto& f : m.expect_failed) std::printf("  EXPECT FAILED %s\n", f.c_str());
  std::printf("  wrote %s/metrics.json, %s/log.csv\n", out_dir.c_str(), out_dir.c_str());
}

int Run(int argc, char** argv) {
  const Args a =
      Parse(argc, argv, 2,
            {"--out", "--seed", "--controller", "--camera", "--video", "--params", "--set"},
            {"--video-slack-events", "--quiet", "--plots"});
  if (a.positional.size() != 1) throw InputError("", "", "hpa run takes one SCENARIO.yaml");
  const Params params = LoadParams(a.Get("--params", DefaultParamsPath()));
  Scenario scenario = LoadWithSets(a.positional[0], a.sets);
  ApplyOverrides(a, &scenario);
  const std::string out_dir = a.Get("--out", "out/" + scenario.name);
  MakeOutputDir(out_dir);

  RunOptions options;
  options.progress = !a.Has("--quiet");
  options.video_path = a.Get("--video");
  options.video_slack_events_only = a.Has("--video-slack-events");
  if (options.video_slack_events_only && options.video_path.empty()) {
    options.video_path = out_dir + "/slack_events.mp4";
  }
  const RunResult result = RunScenario(scenario, params, options);
  WriteText(out_dir + "/metrics.json", MetricsToJson(result.metrics));
  WriteLogCsv(out_dir + "/log.csv", result.rows);
  if (a.Has("--plots")) {
    for (const std::string& png : WriteRunPlots(result, params, out_dir)) {
      if (!a.Has("--quiet")) std::printf("  plot %s\n", png.c_str());
    }
  }
  if (!a.Has("--quiet")) {
    PrintSummary(result.metrics, out_dir);
    if (!options.video_path.empty()) std::printf("  video %s\n", options.video_path.c_str());
  }
  if (result.metrics.run_error) {
    std::fprintf(stderr, "hpa: internal error during the run (results so far are written): %s\n",
                 result.metrics.run_error->c_str());
    return kExitInternal;
  }
  if (result.metrics.crashed && !scenario.expect.Has("crashed")) {
    // no expect block says a crash is fine: an unexpected crash fails the run
    std::fprintf(stderr,
                 "hpa: the vehicle crashed (%s at t = %.3f s) and the scenario does not "
                 "expect a crash\n",
                 result.metrics.crash_reason.value_or("").c_str(),
                 result.metrics.crash_time_s.value_or(0.0));
    return kExitExpectFailed;
  }
  return result.metrics.expect_passed ? kExitOk : kExitExpectFailed;
}

int Compare(int argc, char** argv) {
  const Args a = Parse(argc, argv, 2, {"--out", "--controllers", "--camera", "--params", "--seed"},
                       {"--video-slack-events", "--quiet"});
  if (a.positional.size() != 1) throw InputError("", "", "hpa compare takes one SCENARIO.yaml");
  if (!a.Has("--out")) throw InputError("", "--out", "hpa compare needs --out DIR");
  const Params params = LoadParams(a.Get("--params", DefaultParamsPath()));
  Scenario base = LoadScenario(a.positional[0]);
  ApplyOverrides(a, &base);
  const std::string out_dir = a.Get("--out");
  std::vector<std::string> types;
  std::string list = a.Get("--controllers", "hpa_mpc,nonhybrid_mpc") + ",";
  for (size_t p = 0; (p = list.find(',')) != std::string::npos; list.erase(0, p + 1)) {
    if (p > 0) types.push_back(list.substr(0, p));
  }
  // every name checked before the first run
  if (types.empty()) throw InputError("", "--controllers", "expected a list such as A,B");
  for (const std::string& type : types) CheckControllerType(type, "", "--controllers");
  std::vector<RunResult> results;
  bool all_passed = true;
  bool run_error = false;
  for (const std::string& type : types) {
    Args one = a;
    one.flags["--controller"] = type;
    Scenario s = base;
    ApplyOverrides(one, &s);
    const std::string dir = out_dir + "/" + type;
    MakeOutputDir(dir);
    RunOptions options;
    options.progress = !a.Has("--quiet");
    if (a.Has("--video-slack-events")) {
      options.video_path = dir + "/slack_events.mp4";
      options.video_slack_events_only = true;
    }
    results.push_back(RunScenario(s, params, options));
    WriteText(dir + "/metrics.json", MetricsToJson(results.back().metrics));
    WriteLogCsv(dir + "/log.csv", results.back().rows);
    all_passed = all_passed && results.back().metrics.expect_passed;
    if (results.back().metrics.run_error) {
      std::fprintf(stderr, "hpa: internal error during the %s run (its results are written): %s\n",
                   type.c_str(), results.back().metrics.run_error->c_str());
      run_error = true;
    }
    if (!a.Has("--quiet")) {
      PrintSummary(results.back().metrics, dir);
      if (!options.video_path.empty()) std::printf("  video %s\n", options.video_path.c_str());
    }
  }
  const std::string png = out_dir + "/comparison.png";
  WriteComparisonPlot(results, params, png);
  if (!a.Has("--quiet")) std::printf("comparison plot %s\n", png.c_str());
  if (run_error) return kExitInternal;
  return all_passed ? kExitOk : kExitExpectFailed;
}

int RenderFrame(int argc, char** argv) {
  const Args a = Parse(argc, argv, 2, {"--at", "--out", "--params", "--seed", "--controller"}, {});
  if (a.positional.size() != 1)
    throw InputError("", "", "hpa render-frame takes one SCENARIO.yaml");
  if (!a.Has("--at")) throw InputError("", "--at", "hpa render-frame needs --at T (seconds)");
  if (!a.Has("--out")) throw InputError("", "--out", "hpa render-frame needs --out FILE.png");
  const std::string out_name = a.Get("--out");
  if (out_name.size() < 5 || out_name.compare(out_name.size() - 4, 4, ".png") != 0) {
    throw InputError("", "--out",
                     "the frame is written as PNG: give a FILE.png, got '" + out_name + "'");
  }
  const Params params = LoadParams(a.Get("--params", DefaultParamsPath()));
  Scenario scenario = LoadScenario(a.positional[0]);
  ApplyOverrides(a, &scenario);
  const double at_s = ParseNumber("--at", a.Get("--at"));
  if (at_s < 0 || at_s > scenario.duration_s) {
    throw InputError("", "--at", "expected a time in [0, duration] of the scenario");
  }
  const std::string out = a.Get("--out");
  RunOptions options;
  options.stop_at_s = at_s;
  bool written = false;
  double frame_time_s = at_s;
  options.at_stop = [&](sim::World& world) {
    frame_time_s = world.time_s();
    const cv::Mat frame = world.RenderPayloadCamera();
    try {
      written = cv::imwrite(out, frame);
    } catch (const cv::Exception&) {
      written = false;  // e.g. an extension OpenCV cannot encode
    }
  };
  const RunResult result = RunScenario(scenario, params, options);
  if (result.metrics.run_error) {
    std::fprintf(stderr, "hpa: internal error during the run: %s\n",
                 result.metrics.run_error->c_str());
    return kExitInternal;
  }
  if (!written) throw InputError(out, "--out", "cannot write the PNG (path or extension)");
  if (result.metrics.crashed) {
    std::printf("note: the vehicle crashed at t = %.3f s (%s); the frame is from then\n",
                frame_time_s, result.metrics.crash_reason.value_or("").c_str());
  }
  std::printf("wrote %s (payload camera at t = %.3f s)\n", out.c_str(), frame_time_s);
  return kExitOk;
}

}  // namespace

int HpaMain(int argc, char** argv) {
  // SIGTERM / SIGINT: a run stops at its next tick and writes its metrics and log so far
  std::signal(SIGTERM, RequestStop);
  std::signal(SIGINT, RequestStop);
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") ||
      !std::strcmp(argv[1], "help")) {
    std::fputs(Usage().c_str(), argc < 2 ? stderr : stdout);
    return argc < 2 ? kExitBadInput : kExitOk;
  }
  const std::string command = argv[1];
  for (int i = 2; i < argc && command != "golden" && command != "sweep-diff"; ++i) {
    if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) {
      std::fputs(Usage().c_str(), stdout);
      return kExitOk;
    }
  }
  try {
    if (command == "run") return Run(argc, argv);
    if (command == "compare") return Compare(argc, argv);
    if (command == "render-frame") return RenderFrame(argc, argv);
    if (command == "sweep") return SweepMain(argc, argv);
    if (command == "merge") return MergeMain(argc, argv);
    if (command == "golden") return GoldenMain(argc, argv);
    if (command == "sweep-diff") return SweepDiffMain(argc, argv);
    throw InputError("", "", "unknown command '" + command + "' (see hpa --help)");
  } catch (const InputError& e) {
    std::fprintf(stderr, "hpa: error: %s\n", e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hpa: internal error: %s\n", e.what());
    return kExitInternal;
  }
}

}  // namespace hpa
