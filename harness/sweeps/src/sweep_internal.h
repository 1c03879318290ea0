#pragma once
// Private pieces of `hpa sweep` and `hpa merge`, shared by the files of harness/sweeps/src/
// and their unit tests: results I/O (runs.jsonl records, the output-folder lock), the worker pool
// and the summary.

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "hpa/models/params.h"
#include "hpa/scenarios/scenario.h"
#include "hpa/scenarios/sweep.h"
#include "hpa/sim/gl_backend.h"

namespace hpa::sweep {

/// True if `s` is a whole finite number (then stored in `*v`).
bool IsNumber(const std::string& s, double* v = nullptr);

/// A number with round-trip precision (drawn values are replayed with --set).
std::string FormatNumber(double v);

/// A 16-hex-digit FNV-1a hash of a text: the sweep_id of a sweep's inputs, a data file's hash.
std::string HashText(const std::string& text);

/// Builds the scenario of one run: the base file with the run's values set, validated.
Scenario BuildScenario(const SweepSpec& spec, const SweepRun& run);

/// One parsed line of runs.jsonl.
struct Record {
  int run = -1;
  unsigned long seed = 0;
  std::string sweep_id, sweep_file, base;
  std::vector<std::pair<std::string, std::string>> values;
  std::string controller;    // what flew: a controller type, or the name a flight stack gave
  std::string flight_stack;  // the flight-stack command that flew the run ("": in process)
  bool error = false;
  std::string error_text;
  bool crashed = false;
  bool expect_failed = false;  // any `expect` bound of the scenario failed (crash included)
  double payload_rmse_norm_m = 0, quad_dev_max_m = 0, solve_median_ms = 0, slack_time_s = 0;
  double payload_in_fov = 1;
  double mode_accuracy = 1;
  // metrics.json's estimator.resets (forced accepts) + estimator.cable_reinitialisations (cable
  // filter restarts); 0 if none
  double estimator_restarts = 0;
  std::string line;  // the raw JSON line
};

/// A run whose mode accuracy, in-view fraction or estimator restarts stands out of the runs of its
/// group (see FindOutliers).
struct Outlier {
  const Record* record = nullptr;
  std::string metric;
  double value = 0.0, median = 0.0;
};

/// Finished runs whose mode_accuracy or payload_in_fov_fraction lies below, or whose estimator
/// restarts lie above, the median of their group (the controller and the values of
/// `grid_keys`: a grid cell) by more than 5 scaled median absolute deviations (1.4826 MAD: 5
/// standard deviations of a normal sample) and by more than a floor that matters (0.05 for the
/// fractions, 2 restarts): a run the estimator lost, which no crash flags.
std::vector<Outlier> FindOutliers(const std::vector<Record>& records,
                                  const std::set<std::string>& grid_keys = {});

/// One record per run index, the rule of both the sweep's summary and merge: a run recorded
/// twice with the same outcome counts once; a finished record wins over an error record (a run
/// retried); two different finished records keep the first and add a warning naming the run;
/// a record whose index lies outside [0, expected_runs) is left out with a warning
/// (expected_runs < 0: no bound). Sorted by run index.
std::vector<Record> UniqueRecords(const std::vector<Record>& records, long expected_runs,
                                  std::vector<std::string>* warnings);

/// Reads runs.jsonl; an unreadable line is skipped with a warning naming it.
std::vector<Record> ReadRecords(const std::string& path);

/// One JSON line of runs.jsonl: the run's identity and values, the spec's flight stack (when
/// one flies), then its outcome. `controller` labels what flew; `metrics_json` empty means none;
/// `error` empty means the run finished.
std::string RecordLine(const SweepSpec& spec, const SweepRun& run, const std::string& controller,
                       const std::string& error, const std::string& metrics_json);

/// Takes an exclusive lock on an output folder for the life of this process; a second sweep on
/// the folder is refused (InputError naming the holder's pid).
void LockOutputDir(const std::string& dir);

/// Cuts an unterminated last line off runs.jsonl (a sweep killed mid-write) and says so.
void DropTornLastLine(const std::string& jsonl);

/// Rewrites runs.jsonl without its error records (so those runs run again); returns how many
/// were dropped.
int DropErrorRecords(const std::string& jsonl);

/// One input file of a sweep as it was when the sweep ran.
struct InputFile {
  std::string role;  // "sweep", "base", "reference.file", "params", "scene", "profile NAME"
  std::string path;
  std::optional<std::string> text;  // the whole text, where the snapshot keeps it
  std::string hash;                 // HashText of the text (every file has one)
};

/// The inputs a part of a sweep's runs was flown from after `--resume --allow-changed-inputs`.
struct ResumedInputs {
  std::string inputs_id;  // the changed inputs' hash, as the part's records carry it
  std::vector<InputFile> files;
  std::string flight_stack;                                        // as InputsSnapshot's
  std::vector<std::pair<std::string, std::string>> flight_stacks;  // as InputsSnapshot's
  std::optional<int> runs;                                         // --runs, when given
  std::vector<std::pair<std::string, std::string>> sets;           // --set PATH=VALUE, in order
};

/// DIR/inputs.json: the files a sweep ran from, with its sweep_id, and those of every part
/// resumed with changed inputs.
struct InputsSnapshot {
  std::string sweep_id;
  std::vector<InputFile> files;
  std::string flight_stack;  // the flight-stack command every run flew ("": in process)
  // the stacks factor's named stacks (hpa sweep --flight-stack NAME=CMD, twice or more)
  std::vector<std::pair<std::string, std::string>> flight_stacks;
  std::optional<int> runs;                                // hpa sweep --runs, when given
  std::vector<std::pair<std::string, std::string>> sets;  // hpa sweep --set, in order
  std::vector<ResumedInputs> resumed;  // one per inputs_id, in the order first flown
};

/// Writes DIR/inputs.json from the spec's snapshots unless the folder has one (a resume keeps
/// the first); a resume with changed inputs (spec.inputs_id set) adds their files as a resumed
/// part, once per inputs_id.
void WriteInputsSnapshot(const SweepSpec& spec, const std::string& dir);

/// DIR/inputs.json, or nothing when the folder has none; InputError if it is malformed.
std::optional<InputsSnapshot> ReadInputsSnapshot(const std::string& dir);

/// Copies the first of `from_dirs`' inputs.json of sweep `sweep_id` into `to_dir` (a merge).
void CopyInputsSnapshot(const std::vector<std::string>& from_dirs, const std::string& sweep_id,
                        const std::string& to_dir);

/// What changed between two sweeps' input files, one line per changed YAML key ("base file
/// scenarios/x.yaml: reference.period_s: 5 (A) vs 4 (B)"), and their flight stacks when they
/// differ; empty when the files are the same.
std::vector<std::string> DescribeInputChanges(const InputsSnapshot& a, const InputsSnapshot& b);

/// Wilson score interval (95 %) for k successes in n trials; [0, 1] for n = 0.
std::pair<double, double> Wilson(int k, int n);

/// Bins over a varied quantity: one per distinct value if there are at most 8, else 6 equal
/// bins over [min, max]; each bin is [lo, hi].
std::vector<std::pair<double, double>> MakeBins(const std::vector<double>& values);

/// Index of the bin holding `v` (the last bin for a value past every bin).
int BinOf(const std::vector<std::pair<double, double>>& bins, double v);

/// Writes summary.json, summary.md and crash_rate.png from the records of one sweep.
/// With the sweep's spec (null when unknown) runs are grouped by every grid variable (not only
/// the controller), the main varied quantity is binned over its declared range and labelled with
/// its `label:`.
void WriteSummary(const std::vector<Record>& records, const std::string& dir,
                  const SweepSpec* spec = nullptr);

/// Runs `runs` in up to `jobs` forked worker processes (crash isolation, a time limit per run),
/// each rendering through `gl_backend`; `record` gets each run's JSON line as it finishes, with
/// whether it failed. A stop request (SIGINT / SIGTERM: StopRequested) kills the running workers,
/// records nothing for them or for the runs not started, and returns the signal; 0 when every
/// run finished.
int RunPool(
    const SweepSpec& spec, const std::vector<SweepRun>& runs, const Params& params,
    sim::GlBackend gl_backend, int jobs, const std::string& tmp_dir,
    const std::function<void(const std::string& line, bool failed, const SweepRun&)>& record);

/// `--keep-logs worst:N[:METRIC]`: how many of the worst runs keep their log, by which metric.
struct KeepLogsSpec {
  int count = 0;  // 0: none
  std::string metric = "quad_position_deviation_max_m";
};

/// Parses `worst:N` or `worst:N:METRIC` (a ranked metric of metric_defs.h); InputError naming
/// --keep-logs and the valid metrics otherwise.
KeepLogsSpec ParseKeepLogs(const std::string& text);

/// Replays the `keep.count` worst finished runs of `records` (crashed first, then by the metric's
/// bad end) and writes each one's log.csv and metrics.json to OUT/logs/run_<index>/, warning if
/// a replay's metrics differ from its record.
void KeepWorstLogs(const SweepSpec& spec, const std::vector<Record>& records,
                   const KeepLogsSpec& keep, const std::string& out_dir, const Params& params,
                   sim::GlBackend gl_backend);

}  // namespace hpa::sweep
