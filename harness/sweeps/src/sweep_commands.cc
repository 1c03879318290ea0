// `hpa sweep`: argument parsing, resume and shards, progress, the summary.

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <thread>

#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/scenarios/runner.h"
#include "hpa/sim/camera_image_model.h"
#include "hpa/sim/world.h"
#include "harness/cli/src/cli_parse.h"
#include "harness/cli/src/scenario_commands.h"
#include "harness/sweeps/src/sweep_internal.h"

namespace hpa {

using sweep::Record;

namespace {

// What `hpa sweep` was asked for on its command line.
struct SweepArgs {
  std::string sweep_file, out_dir, shard = "1/1", gl = "osmesa", keep_logs;
  std::vector<std::string> flight_stacks;  // --flight-stack: one CMD, or NAME=CMD per stack
  std::optional<int> runs;                 // --runs: replaces the file's `runs:`
  std::vector<std::string> sets;           // --set PATH=VALUE, in order
  double flight_timeout_s = 10.0;
  int jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  bool resume = false, retry_errors = false, allow_changed_inputs = false;
};

// Adds `hpa sweep`'s options to its parser.
void AddSweepOptions(CLI::App& app, SweepArgs* a) {
  app.add_option("SWEEP.yaml", a->sweep_file, "the sweep file")->required();
  app.add_option("--out", a->out_dir, "output folder (locked while the sweep runs)")->required();
  app.add_option("--runs", a->runs,
                 "N: the sweep's random draws, replacing the file's runs: (times the grid)")
      ->check(CLI::Range(1, 1000000));
  app.add_option("--set", a->sets,
                 "PATH=VALUE: sets one dotted key of the base scenario in every run (repeatable; "
                 "as hpa run --set, e.g. --set duration=2), without copying the sweep file; not "
                 "a key vary draws. --runs and --set are part of the sweep's identity: a resume "
                 "needs the same")
      ->allow_extra_args(false);
  app.add_option("--jobs", a->jobs, "worker processes (default: the number of cores)")
      ->check(CLI::Range(1, 256));
  app.add_option("--shard", a->shard, "K/N: run every N-th run, starting at run K-1 (K = 1..N)");
  app.add_flag("--resume", a->resume, "continue a sweep in DIR, skipping the runs it recorded");
  app.add_flag("--retry-errors", a->retry_errors,
               "with --resume: run again the runs recorded as errors (killed, timed out)");
  app.add_flag("--allow-changed-inputs", a->allow_changed_inputs,
               "with --resume: continue although the sweep or base file changed since DIR's "
               "runs were recorded; new records keep DIR's sweep_id and carry inputs_id, the "
               "hash of the changed inputs");
  app.add_option("--keep-logs", a->keep_logs,
                 "worst:N[:METRIC]: after the sweep, replay the N worst runs (crashes first, then "
                 "by METRIC, default quad_position_deviation_max_m) and keep their log.csv in "
                 "DIR/logs/run_<index>/ (whole sweeps, not shards)");
  app.add_option("--flight-stack", a->flight_stacks,
                 "every run flies this separate flight stack (a shell command started once per "
                 "run, as hpa run --flight-stack; replaces the sweep file's flight_stack:); part "
                 "of the sweep's identity, so --resume and merge refuse another stack. Given "
                 "twice or more, each as NAME=CMD: the stacks are a grid factor (vary key "
                 "flight_stack, its values the NAMEs), every draw flown by each on the same seed")
      ->check([](const std::string& text) { return FlightStackCommandError(text); })
      ->allow_extra_args(false);
  app.add_option("--flight-timeout", a->flight_timeout_s,
                 "with a flight stack: seconds to wait for its whole reply to one tick before "
                 "that run ends with a run error, in [0.001, 3600]")
      ->check(FlightTimeoutError);
  AddGlOption(app, &a->gl);
}

// --shard K/N as whole numbers in range (digits only: no sign, no overflow past kMaxShards).
std::pair<int, int> ParseShard(const std::string& shard) {
  constexpr long kMaxShards = 1000000;
  const size_t slash = shard.find('/');
  const auto whole = [&](const std::string& text) -> long {
    if (text.empty() || text.size() > 7 ||
        text.find_first_not_of("0123456789") != std::string::npos) {
      return -1;
    }
    return std::stol(text);
  };
  const long k = slash == std::string::npos ? -1 : whole(shard.substr(0, slash));
  const long n = slash == std::string::npos ? -1 : whole(shard.substr(slash + 1));
  if (k < 1 || n < 1 || k > n || n > kMaxShards) {
    throw InputError("", "--shard",
                     "expected K/N with 1 <= K <= N <= " + std::to_string(kMaxShards) +
                         " (whole numbers), got '" + shard + "'");
  }
  return {static_cast<int>(k), static_cast<int>(n)};
}

// The command line's changes to the sweep file: one --flight-stack CMD replaces its stack, two
// or more NAME=CMD are the stacks factor; --runs; each --set PATH=VALUE.
SweepOverrides OverridesOf(const SweepArgs& a) {
  SweepOverrides overrides;
  overrides.runs = a.runs;
  for (const std::string& text : a.sets) overrides.sets.push_back(ParseSetArgument(text));
  if (a.flight_stacks.size() == 1) overrides.flight_stack = a.flight_stacks.front();
  if (a.flight_stacks.size() < 2) return overrides;
  for (const std::string& text : a.flight_stacks) {
    const size_t eq = text.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw InputError("", "--flight-stack",
                       "given " + std::to_string(a.flight_stacks.size()) +
                           " times, so each is NAME=CMD (a stack of the factor), got '" + text +
                           "'");
    }
    overrides.flight_stacks.emplace_back(text.substr(0, eq), text.substr(eq + 1));
  }
  return overrides;
}

// Refuses the flags that only make sense with --resume when it is not given.
void CheckResumeFlags(const SweepArgs& a) {
  if (a.retry_errors && !a.resume) {
    throw InputError("", "--retry-errors", "only with --resume (it re-runs recorded errors)");
  }
  if (a.allow_changed_inputs && !a.resume) {
    throw InputError("", "--allow-changed-inputs", "only with --resume");
  }
}

// Readies runs.jsonl for appending: refuses anything but a regular file, cuts a torn last line
// and, with --retry-errors, drops the error records so those runs run again.
void PrepareResultsFile(const std::string& jsonl, bool retry_errors) {
  struct stat st;
  if (lstat(jsonl.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    throw InputError(jsonl, "", "not a regular file (a link, a device or a folder)");
  }
  sweep::DropTornLastLine(jsonl);
  if (retry_errors) {
    const int dropped = sweep::DropErrorRecords(jsonl);
    std::printf("--retry-errors: %d error record%s dropped from %s; those runs run again\n",
                dropped, dropped == 1 ? "" : "s", jsonl.c_str());
  }
}

// The runs runs.jsonl already records, for a resume to skip. Refuses to mix sweeps in one
// folder unless told that the inputs changed on purpose, then the new records say so (the
// spec keeps the folder's sweep_id and carries inputs_id); refuses recorded runs without
// --resume.
std::set<int> RecordedRuns(const std::string& jsonl, const SweepArgs& a, SweepSpec* spec) {
  std::set<int> done;
  const std::string inputs_id = spec->sweep_id;
  const auto shown = [](const std::string& command) {
    return command.empty() ? std::string("in process") : "by the flight stack '" + command + "'";
  };
  for (const Record& r : sweep::ReadRecords(jsonl)) {
    // one sweep flies one stack (or each of its stacks factor): its runs compare with each other
    // only then (not even --allow-changed-inputs mixes them)
    SweepRun recorded;
    recorded.values = r.values;
    const std::string stack = FlightStackOf(*spec, recorded);
    if (r.flight_stack != stack) {
      throw InputError(jsonl, "",
                       "holds runs flown " + shown(r.flight_stack) + " (run " +
                           std::to_string(r.run) + "), but this sweep's runs are flown " +
                           shown(stack) + ": one sweep flies one flight stack; use another --out");
    }
    if (r.sweep_id != spec->sweep_id) {
      if (!a.allow_changed_inputs || !done.empty()) {
        throw InputError(jsonl, "",
                         "holds runs of a different sweep (sweep_id " + r.sweep_id + ", the " +
                             "inputs now hash to " + inputs_id + "): the sweep or base file " +
                             "changed (or --runs, --set or a data file of hpa); use another " +
                             "--out, or --resume --allow-changed-inputs to continue with the " +
                             "changed inputs");
      }
      std::fprintf(stderr,
                   "hpa: warning: the sweep or base file changed since %s was recorded (or "
                   "--runs, --set or a data file of hpa; sweep_id %s, now %s); the runs still to "
                   "do use the changed inputs, their records carry inputs_id %s and inputs.json "
                   "adds them under `resumed`\n",
                   jsonl.c_str(), r.sweep_id.c_str(), inputs_id.c_str(), inputs_id.c_str());
      spec->sweep_id = r.sweep_id;
      spec->inputs_id = inputs_id;
    }
    done.insert(r.run);
  }
  if (!done.empty() && !a.resume) {
    throw InputError(jsonl, "",
                     "already holds " + std::to_string(done.size()) +
                         " runs; pass --resume to continue or use another --out");
  }
  return done;
}

// Appends each finished run's line to runs.jsonl, synced so that a killed sweep loses no
// finished run, and shows the progress: a bar on a terminal, a line per run otherwise.
class ResultsAppender {
 public:
  using Clock = std::chrono::steady_clock;

  ResultsAppender(FILE* out, const std::string& jsonl, size_t total)
      : out_(out), jsonl_(jsonl), total_(total), tty_(isatty(STDOUT_FILENO)) {}

  // Records one run's line and updates the progress shown.
  void Append(const std::string& line, bool failed, const SweepRun& run) {
    const long before = std::ftell(out_);
    errno = 0;
    if (std::fprintf(out_, "%s\n", line.c_str()) < 0 || std::fflush(out_) != 0) {
      // a full disk or the file-size limit: the part of the line written is cut off again, so
      // the file ends with the last whole record
      const int write_errno = errno;
      if (before >= 0 && ftruncate(fileno(out_), before) != 0) {
        std::fprintf(stderr, "hpa: %s: cannot cut the record written in part\n", jsonl_.c_str());
      }
      throw OutputError(jsonl_, "cannot append a run's record: " + WriteErrorText(write_errno));
    }
    fsync(fileno(out_));
    ++finished_;
    failures_ += failed ? 1 : 0;
    const double eta = elapsed_s() / finished_ * (total_ - finished_);
    if (tty_) {
      const int width = 30,
                filled = static_cast<int>(width * finished_ / std::max<size_t>(1, total_));
      std::printf("\r[%s%s] %zu/%zu  failures %d  ETA %.0f s   ", std::string(filled, '#').c_str(),
                  std::string(width - filled, '.').c_str(), finished_, total_, failures_, eta);
    } else {
      std::printf("run %d done (%zu/%zu, failures %d, ETA %.0f s)\n", run.index, finished_, total_,
                  failures_, eta);
    }
    std::fflush(stdout);
  }

  // Wall time since the appender was made, when the runs started.
  double elapsed_s() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }
  // Runs recorded so far.
  size_t finished() const { return finished_; }
  // Runs recorded as failed so far.
  int failures() const { return failures_; }
  // Whether stdout is a terminal (the progress is then a bar redrawn in place).
  bool tty() const { return tty_; }

 private:
  FILE* out_;
  std::string jsonl_;
  size_t total_;
  bool tty_;
  size_t finished_ = 0;
  int failures_ = 0;
  Clock::time_point start_ = Clock::now();
};

// After a whole sweep: its summary from the unique records and, with --keep-logs, the worst
// runs' logs; after a shard: how to join the shards (a shard's worst runs are not the sweep's).
void FinishSweep(const SweepSpec& spec, const std::string& jsonl, const std::string& out_dir,
                 int shard_k, int shard_n, const sweep::KeepLogsSpec& keep, const Params& params,
                 sim::GlBackend gl_backend) {
  if (shard_n == 1) {
    std::vector<std::string> warnings;
    const std::vector<Record> unique =
        sweep::UniqueRecords(sweep::ReadRecords(jsonl), SweepRunCount(spec), &warnings);
    sweep::WriteSummary(unique, out_dir, &spec);
    for (const std::string& w : warnings) std::fprintf(stderr, "hpa: warning: %s\n", w.c_str());
    std::printf("summary: %s/summary.md, %s/summary.json, %s/crash_rate.png\n", out_dir.c_str(),
                out_dir.c_str(), out_dir.c_str());
    if (keep.count > 0) sweep::KeepWorstLogs(spec, unique, keep, out_dir, params, gl_backend);
  } else {
    if (keep.count > 0)
      std::printf("--keep-logs: not for a shard (the worst runs are the sweep's)\n");
    std::printf("shard %d/%d done; join the shards with: hpa merge DIR... --out DIR\n", shard_k,
                shard_n);
  }
}

// The first rendered run's world renders one frame here, before the workers fork: each of them
// then starts with a GL context whose shaders are compiled (Renderer::PrewarmForFork).
void PrewarmRenderer(const SweepSpec& spec, const std::vector<SweepRun>& runs, const Params& params,
                     sim::GlBackend gl_backend) {
  // the first runs only (a grid's first cells): building every run of a large analytic sweep
  // to find none rendered would cost more than the warm-up saves
  constexpr size_t kRunsLookedAt = 64;
  try {
    for (size_t i = 0; i < std::min(runs.size(), kRunsLookedAt); ++i) {
      const Scenario scenario = sweep::BuildScenario(spec, runs[i]);
      if (scenario.estimation.camera != "render" || scenario.estimation.ground_truth) continue;
      sim::Renderer::PrewarmForFork(WorldConfigOf(scenario, params, gl_backend));
      return;
    }
  } catch (const std::exception& e) {
    // each run then creates its own context, and reports its own error if it cannot
    std::fprintf(stderr, "sweep: no shared GL context (%s)\n", e.what());
  }
}

}  // namespace

int SweepMain(int argc, char** argv) {
  SweepArgs a;
  CLI::App app{
      "Runs a Monte Carlo sweep: one JSON line per run in DIR/runs.jsonl, then DIR/summary.md, "
      "summary.json and crash_rate.png.",
      "hpa sweep"};
  AddSweepOptions(app, &a);
  if (const auto code = ParseCommandLine(app, argc, argv)) return *code;
  const sim::GlBackend gl_backend = ParseGlOption(a.gl);  // every worker renders with it
  const sweep::KeepLogsSpec keep =
      a.keep_logs.empty() ? sweep::KeepLogsSpec{} : sweep::ParseKeepLogs(a.keep_logs);
  const auto [shard_k, shard_n] = ParseShard(a.shard);
  CheckResumeFlags(a);

  SweepOverrides overrides = OverridesOf(a);
  SweepSpec spec = LoadSweep(a.sweep_file, overrides);
  spec.flight_timeout_s = a.flight_timeout_s;
  const Params params = LoadParams(DefaultParamsPath());
  const std::vector<SweepRun> all_runs = ExpandSweep(spec);
  std::vector<SweepRun> runs = SelectShard(all_runs, shard_k, shard_n);
  MakeOutputDir(a.out_dir);
  const std::string jsonl = a.out_dir + "/runs.jsonl";
  sweep::LockOutputDir(a.out_dir);
  PrepareResultsFile(jsonl, a.retry_errors);
  // resume: skip what is recorded
  const std::set<int> done = RecordedRuns(jsonl, a, &spec);
  sweep::WriteInputsSnapshot(spec, a.out_dir);
  runs.erase(std::remove_if(runs.begin(), runs.end(),
                            [&](const SweepRun& r) { return done.count(r.index) > 0; }),
             runs.end());
  const std::string tmp_dir = a.out_dir + "/.running";
  MakeOutputDir(tmp_dir);
  FILE* out = std::fopen(jsonl.c_str(), "a");
  if (!out) throw OutputError(jsonl, "cannot append to the results file");

  std::printf("sweep %s: %zu runs in all, shard %d/%d: %zu to run (%zu already done), %d jobs\n",
              spec.file.c_str(), all_runs.size(), shard_k, shard_n, runs.size(), done.size(),
              a.jobs);
  if (!spec.flight_stack.empty()) {
    std::printf("each run flies its own flight stack: %s\n", spec.flight_stack.c_str());
  }
  for (const auto& [name, command] : spec.flight_stacks) {
    std::printf("each draw is flown by the stack %s (its own process per run): %s\n", name.c_str(),
                command.c_str());
  }
  std::fflush(stdout);
  ResultsAppender results(out, jsonl, runs.size());
  // the rendered camera's tables, once here rather than in every forked run
  sim::CameraImageModel::PrepareSharedTables(params);
  PrewarmRenderer(spec, runs, params, gl_backend);
  const int stopped_by =
      sweep::RunPool(spec, runs, params, gl_backend, a.jobs, tmp_dir,
                     [&](const std::string& line, bool failed, const SweepRun& run) {
                       results.Append(line, failed, run);
                     });
  std::fclose(out);
  rmdir(tmp_dir.c_str());
  if (stopped_by != 0) {
    std::printf(
        "%ssweep stopped by signal %d (%s): %zu runs recorded in %s, the rest not started "
        "or killed unrecorded; continue with --resume\n",
        results.tty() ? "\n" : "", stopped_by, strsignal(stopped_by), results.finished(),
        jsonl.c_str());
    return kExitStoppedBySignal + stopped_by;
  }
  if (results.tty()) std::printf("\n");
  const double wall_s = results.elapsed_s();
  std::printf(
      "sweep done: %zu runs, %d failures in %.1f s wall (%.1f runs per minute); "
      "results in %s\n",
      results.finished(), results.failures(), wall_s,
      results.finished() * 60.0 / std::max(wall_s, 1e-9), jsonl.c_str());
  FinishSweep(spec, jsonl, a.out_dir, shard_k, shard_n, keep, params, gl_backend);
  return 0;
}

}  // namespace hpa
