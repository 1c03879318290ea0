// `hpa merge`: sweep shards (or resumed parts) joined into one runs.jsonl and its summary.

#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "hpa/scenarios/metrics.h"
#include "hpa/scenarios/sweep.h"
#include "harness/cli/src/cli_parse.h"
#include "harness/cli/src/scenario_commands.h"
#include "harness/sweeps/src/sweep_internal.h"

namespace hpa {

using sweep::Record;

namespace {

// Every record of the shards' runs.jsonl files, all of one sweep (whose id goes to *sweep_id).
std::vector<Record> ReadShardRecords(const std::vector<std::string>& dirs, std::string* sweep_id) {
  std::vector<Record> all;
  for (const std::string& d : dirs) {
    const std::string path = d + "/runs.jsonl";
    struct stat st;
    if (stat(path.c_str(), &st) != 0) throw InputError(path, "", "no runs.jsonl in this folder");
    if (!S_ISREG(st.st_mode) || access(path.c_str(), R_OK) != 0) {
      throw InputError(path, "", "not a readable file");
    }
    for (Record& r : sweep::ReadRecords(path)) {
      if (sweep_id->empty()) *sweep_id = r.sweep_id;
      if (r.sweep_id != *sweep_id) {
        throw InputError(path, "sweep_id",
                         "mixes sweeps (" + r.sweep_id + " vs " + *sweep_id +
                             "); merge only shards of one sweep");
      }
      all.push_back(std::move(r));
    }
  }
  return all;
}

// The sweep file's spec, with the flight stack its runs recorded and the --runs and --set the
// folders' inputs.json recorded, when it is still the sweep recorded (same sweep_id), else
// nothing: then how many runs the sweep has is unknown.
std::optional<SweepSpec> SameSweep(const std::string& sweep_file, const std::string& sweep_id,
                                   const std::string& flight_stack,
                                   const std::vector<std::string>& dirs) {
  SweepOverrides overrides;
  overrides.flight_stack = flight_stack;
  for (const std::string& dir : dirs) {
    std::optional<sweep::InputsSnapshot> inputs;
    try {
      inputs = sweep::ReadInputsSnapshot(dir);
    } catch (const InputError&) {
    }
    if (!inputs || inputs->sweep_id != sweep_id) continue;
    overrides.runs = inputs->runs;
    overrides.sets = inputs->sets;
    overrides.flight_stacks = inputs->flight_stacks;
    break;
  }
  try {
    SweepSpec loaded = LoadSweep(sweep_file, overrides);
    if (loaded.sweep_id == sweep_id) return loaded;
  } catch (const InputError&) {
  }
  return std::nullopt;
}

// Writes the merged runs.jsonl, replaced in one rename: a folder that is also one of the
// inputs is read before it is written.
void WriteMergedRuns(const std::vector<Record>& records, const std::string& out_dir) {
  std::string merged;
  for (const Record& r : records) merged += r.line + "\n";
  WriteFileAtomic(out_dir + "/runs.jsonl", merged);
}

// Names the runs of the sweep that no folder recorded: the merge is incomplete (exit 1);
// 0 when every run is there.
int ReportMissingRuns(const std::vector<Record>& records, long expected) {
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

}  // namespace

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
  std::string sweep_id;
  const std::vector<Record> all = ReadShardRecords(dirs, &sweep_id);
  if (all.empty()) throw InputError("", "DIR", "no runs recorded in the folders given");
  // how many runs the sweep has: from its file when it is still the same sweep, else unknown
  const std::optional<SweepSpec> spec =
      SameSweep(all.front().sweep_file, sweep_id, all.front().flight_stack, dirs);
  const long expected = spec ? SweepRunCount(*spec) : -1;
  std::vector<std::string> warnings;
  const std::vector<Record> records = sweep::UniqueRecords(all, expected, &warnings);
  for (const std::string& w : warnings) std::fprintf(stderr, "hpa: warning: %s\n", w.c_str());
  MakeOutputDir(out_dir);
  WriteMergedRuns(records, out_dir);
  sweep::CopyInputsSnapshot(dirs, sweep_id, out_dir);
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
  return ReportMissingRuns(records, expected);
}

}  // namespace hpa
