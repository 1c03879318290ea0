// `hpa sweep` and `hpa merge`: argument parsing, resume and shards, progress, the summary.

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

#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/scenarios/runner.h"
#include "scenarios/src/tools/cli_parse.h"
#include "scenarios/src/tools/sweep/sweep_internal.h"

namespace hpa {

using sweep::Record;

int SweepMain(int argc, char** argv) {
  std::string sweep_file, out_dir, shard = "1/1", gl = "osmesa", keep_logs;
  int jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  bool resume = false, retry_errors = false, allow_changed_inputs = false;
  CLI::App app{
      "Runs a Monte Carlo sweep: one JSON line per run in DIR/runs.jsonl, then DIR/summary.md, "
      "summary.json and crash_rate.png.",
      "hpa sweep"};
  app.add_option("SWEEP.yaml", sweep_file, "the sweep file")->required();
  app.add_option("--out", out_dir, "output folder (locked while the sweep runs)")->required();
  app.add_option("--jobs", jobs, "worker processes (default: the number of cores)")
      ->check(CLI::Range(1, 256));
  app.add_option("--shard", shard, "K/N: run every N-th run, starting at run K-1 (K = 1..N)");
  app.add_flag("--resume", resume, "continue a sweep in DIR, skipping the runs it recorded");
  app.add_flag("--retry-errors", retry_errors,
               "with --resume: run again the runs recorded as errors (killed, timed out)");
  app.add_flag("--allow-changed-inputs", allow_changed_inputs,
               "with --resume: continue although the sweep or base file changed since DIR's "
               "runs were recorded; new records keep DIR's sweep_id and carry inputs_id, the "
               "hash of the changed inputs");
  app.add_option("--keep-logs", keep_logs,
                 "worst:N[:METRIC]: after the sweep, replay the N worst runs (crashes first, then "
                 "by METRIC, default quad_position_deviation_max_m) and keep their log.csv in "
                 "DIR/logs/run_<index>/ (whole sweeps, not shards)");
  AddGlOption(app, &gl);
  if (const auto code = ParseCommandLine(app, argc, argv)) return *code;
  const sim::GlBackend gl_backend = ParseGlOption(gl);  // every worker renders with it
  const sweep::KeepLogsSpec keep =
      keep_logs.empty() ? sweep::KeepLogsSpec{} : sweep::ParseKeepLogs(keep_logs);
  // K/N as whole numbers in range (digits only: no sign, no overflow past kMaxShards)
  constexpr long kMaxShards = 1000000;
  int shard_k = 1, shard_n = 1;
  {
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
    shard_k = static_cast<int>(k);
    shard_n = static_cast<int>(n);
  }
  if (retry_errors && !resume) {
    throw InputError("", "--retry-errors", "only with --resume (it re-runs recorded errors)");
  }
  if (allow_changed_inputs && !resume) {
    throw InputError("", "--allow-changed-inputs", "only with --resume");
  }

  SweepSpec spec = LoadSweep(sweep_file);
  const Params params = LoadParams(DefaultParamsPath());
  const std::vector<SweepRun> all_runs = ExpandSweep(spec);
  std::vector<SweepRun> runs = SelectShard(all_runs, shard_k, shard_n);
  MakeOutputDir(out_dir);
  const std::string jsonl = out_dir + "/runs.jsonl";
  sweep::LockOutputDir(out_dir);
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

  // resume: skip what is recorded; refuse to mix sweeps in one folder unless told that the
  // inputs changed on purpose, then the new records say so (inputs_id)
  std::set<int> done;
  const std::string inputs_id = spec.sweep_id;
  for (const Record& r : sweep::ReadRecords(jsonl)) {
    if (r.sweep_id != spec.sweep_id) {
      if (!allow_changed_inputs || !done.empty()) {
        throw InputError(jsonl, "",
                         "holds runs of a different sweep (sweep_id " + r.sweep_id + ", the " +
                             "inputs now hash to " + inputs_id + "): the sweep or base file " +
                             "changed; use another --out, or --resume --allow-changed-inputs " +
                             "to continue with the changed inputs");
      }
      std::fprintf(stderr,
                   "hpa: warning: the sweep or base file changed since %s was recorded (sweep_id "
                   "%s, now %s); the runs still to do use the changed inputs and their records "
                   "carry inputs_id %s\n",
                   jsonl.c_str(), r.sweep_id.c_str(), inputs_id.c_str(), inputs_id.c_str());
      spec.sweep_id = r.sweep_id;
      spec.inputs_id = inputs_id;
    }
    done.insert(r.run);
  }
  if (!done.empty() && !resume) {
    throw InputError(jsonl, "",
                     "already holds " + std::to_string(done.size()) +
                         " runs; pass --resume to continue or use another --out");
  }
  runs.erase(std::remove_if(runs.begin(), runs.end(),
                            [&](const SweepRun& r) { return done.count(r.index) > 0; }),
             runs.end());
  const std::string tmp_dir = out_dir + "/.running";
  MakeOutputDir(tmp_dir);
  FILE* out = std::fopen(jsonl.c_str(), "a");
  if (!out) throw OutputError(jsonl, "cannot append to the results file");

  std::printf("sweep %s: %zu runs in all, shard %d/%d: %zu to run (%zu already done), %d jobs\n",
              spec.file.c_str(), all_runs.size(), shard_k, shard_n, runs.size(), done.size(), jobs);
  std::fflush(stdout);
  const bool tty = isatty(STDOUT_FILENO);
  size_t finished = 0;
  int failures = 0;
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto record = [&](const std::string& line, bool failed, const SweepRun& run) {
    if (std::fprintf(out, "%s\n", line.c_str()) < 0 || std::fflush(out) != 0) {
      throw OutputError(jsonl, std::string("cannot append: ") + std::strerror(errno));
    }
    fsync(fileno(out));
    ++finished;
    failures += failed ? 1 : 0;
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    const double eta = elapsed / finished * (runs.size() - finished);
    if (tty) {
      const int width = 30,
                filled = static_cast<int>(width * finished / std::max<size_t>(1, runs.size()));
      std::printf("\r[%s%s] %zu/%zu  failures %d  ETA %.0f s   ", std::string(filled, '#').c_str(),
                  std::string(width - filled, '.').c_str(), finished, runs.size(), failures, eta);
    } else {
      std::printf("run %d done (%zu/%zu, failures %d, ETA %.0f s)\n", run.index, finished,
                  runs.size(), failures, eta);
    }
    std::fflush(stdout);
  };
  const int stopped_by = sweep::RunPool(spec, runs, params, gl_backend, jobs, tmp_dir, record);
  std::fclose(out);
  rmdir(tmp_dir.c_str());
  if (stopped_by != 0) {
    std::printf(
        "%ssweep stopped by signal %d (%s): %zu runs recorded in %s, the rest not started "
        "or killed unrecorded; continue with --resume\n",
        tty ? "\n" : "", stopped_by, strsignal(stopped_by), finished, jsonl.c_str());
    return 128 + stopped_by;
  }
  if (tty) std::printf("\n");
  const double wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  std::printf(
      "sweep done: %zu runs, %d failures in %.1f s wall (%.1f runs per minute); "
      "results in %s\n",
      finished, failures, wall_s, finished * 60.0 / std::max(wall_s, 1e-9), jsonl.c_str());
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
  return 0;
}

int MergeMain(int argc, char** argv) {
  std::vector<std::string> dirs;
  std::string out_dir;
  CLI::App app{
      "Joins sweep shards (or resumed parts) into one runs.jsonl and its summary. One record per "
      "run (a finished record wins over an error; two different finished records keep the first, "
      "with a warning; runs outside the sweep are left out, with a warning). Exits 1, after "
      "writing what it has, when runs of the sweep are missing (a shard not merged or not "
      "finished); 2 when the folders hold no runs or mix sweeps.",
      "hpa merge"};
  app.add_option("DIR", dirs, "sweep output folders, each with a runs.jsonl")->required();
  app.add_option("--out", out_dir, "output folder")->required();
  if (const auto code = ParseCommandLine(app, argc, argv)) return *code;
  std::vector<Record> all;
  std::string sweep_id;
  for (const std::string& d : dirs) {
    const std::string path = d + "/runs.jsonl";
    struct stat st;
    if (stat(path.c_str(), &st) != 0) throw InputError(path, "", "no runs.jsonl in this folder");
    if (!S_ISREG(st.st_mode) || access(path.c_str(), R_OK) != 0) {
      throw InputError(path, "", "not a readable file");
    }
    for (Record& r : sweep::ReadRecords(path)) {
      if (sweep_id.empty()) sweep_id = r.sweep_id;
      if (r.sweep_id != sweep_id) {
        throw InputError(path, "sweep_id",
                         "mixes sweeps (" + r.sweep_id + " vs " + sweep_id +
                             "); merge only shards of one sweep");
      }
      all.push_back(std::move(r));
    }
  }
  if (all.empty()) throw InputError("", "DIR", "no runs recorded in the folders given");
  // how many runs the sweep has: from its file when it is still the same sweep, else unknown
  long expected = -1;
  std::optional<SweepSpec> spec;
  try {
    SweepSpec loaded = LoadSweep(all.front().sweep_file);
    if (loaded.sweep_id == sweep_id) {
      expected = SweepRunCount(loaded);
      spec = std::move(loaded);
    }
  } catch (const InputError&) {
  }
  std::vector<std::string> warnings;
  const std::vector<Record> records = sweep::UniqueRecords(all, expected, &warnings);
  for (const std::string& w : warnings) std::fprintf(stderr, "hpa: warning: %s\n", w.c_str());
  MakeOutputDir(out_dir);
  std::string merged;
  for (const Record& r : records) merged += r.line + "\n";
  // replaced in one rename: a folder that is also one of the inputs is read before it is written
  sweep::WriteFileChecked(out_dir + "/runs.jsonl.tmp", merged);
  if (std::rename((out_dir + "/runs.jsonl.tmp").c_str(), (out_dir + "/runs.jsonl").c_str()) != 0) {
    throw OutputError(out_dir + "/runs.jsonl", std::strerror(errno));
  }
  sweep::WriteSummary(records, out_dir, spec ? &*spec : nullptr);
  std::printf(
      "merged %zu runs from %zu folders into %s (summary.md, summary.json, crash_rate.png)\n",
      records.size(), dirs.size(), out_dir.c_str());
  // runs the sweep has that no folder recorded: the merge is incomplete (exit 1)
  if (expected < 0) {
    std::fprintf(stderr,
                 "hpa: warning: the sweep file %s is gone or changed: missing runs not checked\n",
                 all.front().sweep_file.c_str());
    return 0;
  }
  std::vector<int> missing;
  size_t next = 0;
  for (int index = 0; index < expected; ++index) {
    while (next < records.size() && records[next].run < index) ++next;
    if (next < records.size() && records[next].run == index) continue;
    missing.push_back(index);
  }
  if (missing.empty()) return 0;
  std::string listed;
  for (size_t i = 0; i < std::min<size_t>(10, missing.size()); ++i) {
    listed += (listed.empty() ? "" : ", ") + std::to_string(missing[i]);
  }
  std::fprintf(stderr,
               "hpa: merge incomplete: %zu of %ld runs missing (%s%s): a shard not merged or not "
               "finished; the merged runs are written\n",
               missing.size(), expected, listed.c_str(), missing.size() > 10 ? ", ..." : "");
  return 1;
}

}  // namespace hpa
