#pragma once
// Monte Carlo sweeps (docs/design.md section 6): expansion of `vary` into runs, parallel worker
// processes with crash isolation, JSON-lines results, shards, resume, merge and summaries.

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace hpa {

/// One distribution of a `vary` entry.
struct VarySpec {
  std::string path;  // dotted path into the scenario, e.g. events.1.to.2
  enum class Kind { kUniform, kNormal, kGrid, kList } kind = Kind::kUniform;
  double a = 0.0, b = 0.0;          // uniform [a, b] or normal (mean a, sigma b)
  std::vector<std::string> values;  // grid values (product) or list values (draw i -> i % n)
  std::string label;                // axis label with its unit (`label:`), e.g. "mass [kg]"
};

/// A sweep file, validated.
struct SweepSpec {
  std::string file;
  std::string sweep_text;  // the sweep file's text when loaded (hashed into sweep_id)
  std::string base_path;   // scenario file, resolved against the sweep's folder
  std::string base_text;   // its text when the sweep was loaded: every run uses this snapshot
  // a csv reference's file and its text when the sweep was loaded (every run flies the text);
  // unset when the base has no csv reference or the sweep varies the reference
  std::string reference_csv_path;
  std::optional<std::string> reference_csv_text;
  int runs = 1;  // random draws; grids multiply them
  unsigned long seed = 1;
  double time_limit_s = 600.0;  // per run; a run past it is killed and recorded as an error
  std::vector<VarySpec> vary;
  // the separate flight stack every run flies (`flight_stack:`, or `hpa sweep --flight-stack`,
  // which replaces it): a shell command, started once per run; empty: the flight code in
  // process. Part of the sweep_id: a resume or merge with another stack is refused
  std::string flight_stack;
  // the named stacks of `hpa sweep --flight-stack NAME=CMD`, given twice or more, in order:
  // a grid factor (the vary entry kStackFactor, whose values are the NAMEs), every draw flown
  // by each stack on the same seed. Empty: flight_stack flies every run
  std::vector<std::pair<std::string, std::string>> flight_stacks;
  double flight_timeout_s = 10.0;  // longest wait for the stack's whole reply to one tick
  std::string sweep_id;            // hash of the sweep and base files: merge refuses mixes
  std::string inputs_id;           // set when a resume continues with changed inputs: their hash
  // `hpa sweep --runs N` when given (it replaced the file's `runs:`), for inputs.json
  std::optional<int> runs_override;
  // `hpa sweep --set PATH=VALUE`, in order: set in every run, after its drawn and grid values
  // (a set key is never a vary key, inside one or holding one), so each record's `values`
  // names it
  std::vector<std::pair<std::string, std::string>> sets;
};

/// The vary path of the stacks factor: each run's value is the NAME of the stack that flies it
/// (not a scenario key: the run's scenario never sees it).
constexpr char kStackFactor[] = "flight_stack";

/// What `hpa sweep`'s command line changes in a sweep file without copying it.
struct SweepOverrides {
  std::string flight_stack;  // replaces the file's `flight_stack:` ("": the file's)
  // --flight-stack NAME=CMD given twice or more: the stacks as a grid factor (replaces the
  // file's `flight_stack:`)
  std::vector<std::pair<std::string, std::string>> flight_stacks;
  std::optional<int> runs;                                // replaces the file's `runs:`
  std::vector<std::pair<std::string, std::string>> sets;  // --set PATH=VALUE, in order
};

/// One expanded run: which draw, which grid cell, its seed and its values.
struct SweepRun {
  int index = 0;  // 0 .. runs * grid_size - 1
  int draw = 0;
  unsigned long seed = 0;  // scenario seed (same for every grid value of a draw)
  std::vector<std::pair<std::string, std::string>> values;  // path -> YAML scalar text
};

/// The shell command of the separate flight stack that flies `run` ("": in process): the named
/// stack of its kStackFactor value, else the spec's flight_stack.
std::string FlightStackOf(const SweepSpec& spec, const SweepRun& run);

/// Loads and validates a sweep file: every expanded run must be a valid scenario (each drawn
/// value within its key's range), else InputError naming the run and its values. A non-empty
/// `flight_stack` (hpa sweep --flight-stack) replaces the file's `flight_stack:`.
SweepSpec LoadSweep(const std::string& path, const std::string& flight_stack = "");

/// LoadSweep with the command line's overrides: --flight-stack, --runs (1 .. 1 000 000) and
/// --set PATH=VALUE (a scenario key set in every run, as `hpa run --set`; InputError naming
/// --set for a bad value or a key that `vary` draws). The overrides are part of the sweep_id,
/// so a resume needs the same ones (or --allow-changed-inputs).
SweepSpec LoadSweep(const std::string& path, const SweepOverrides& overrides);

/// Expands the sweep into its runs (deterministic in the sweep seed).
std::vector<SweepRun> ExpandSweep(const SweepSpec& spec);

/// The data files every run of a sweep reads, by role ("params", "scene", "profile flight"):
/// hashed into the sweep_id, so a resume refuses them changed, and kept in inputs.json.
std::vector<std::pair<std::string, std::string>> DataInputFiles();

/// How many runs the sweep has: its draws times its grid cells (LoadSweep keeps it at most
/// kMaxSweepRuns).
long SweepRunCount(const SweepSpec& spec);

/// The most runs one sweep may have (draws times grid cells).
constexpr long kMaxSweepRuns = 1000000;

/// The runs of shard K of N (K = 1..N): every N-th run, starting at index K - 1; the N shards
/// partition the runs.
std::vector<SweepRun> SelectShard(const std::vector<SweepRun>& runs, int shard_k, int shard_n);

/// `hpa sweep` entry point; returns the exit code.
int SweepMain(int argc, char** argv);

/// `hpa merge` entry point; returns the exit code.
int MergeMain(int argc, char** argv);

}  // namespace hpa
