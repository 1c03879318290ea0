#pragma once
// Change indication for CI: the metrics of every shipped scenario (its own seed and controller)
// are kept in a committed golden file, and any change beyond a per-key tolerance is reported.
// A deliberate change rewrites the file (`hpa golden --update --reason "..."`) in the same
// commit, so the file's history is the history of the controllers' behaviour.

#include <string>
#include <vector>

namespace hpa {

/// What `hpa golden` does.
struct GoldenOptions {
  std::string golden_path;  // the golden file (scenarios/ci/golden.json by default)
  std::string from_dir;     // read FROM/<name>/metrics.json (ctest's outputs) instead of running
  bool update = false;      // rewrite the golden file from the current metrics
  std::string reason;       // one line, required with update: why the behaviour changed
  bool quiet = false;       // no per-scenario progress lines
  bool exact = false;       // every value bit for bit: the file's tolerances are ignored
};

/// Shipped scenarios the golden file covers, as names relative to scenarios/ without ".yaml"
/// ("hover", "ci/gripper_pull_truth"), sorted.
std::vector<std::string> GoldenScenarioNames();

/// Result of comparing one metrics.json against its golden copy.
struct GoldenDiff {
  std::vector<std::string> changes;   // "payload_rmse_m.0: 0.0123 -> 0.0151 (tolerance 1.2e-05)"
  std::vector<std::string> new_keys;  // keys the golden copy lacks (reported, not a change)
};

/// Compares `metrics_json` with `golden_json` (both metrics.json texts, timing fields ignored)
/// under the tolerances of `tolerances_json` ({"default": {"rel", "abs"}, "keys": {...}}).
GoldenDiff CompareWithGolden(const std::string& metrics_json, const std::string& golden_json,
                             const std::string& tolerances_json);

/// Runs (or reads) every golden scenario and compares or updates; returns the exit code:
/// 0 unchanged (or updated), 1 a metric changed beyond its tolerance, 2 bad input.
int RunGolden(const GoldenOptions& options);

/// `hpa golden` entry point (argv[1] is "golden"); returns the exit code.
int GoldenMain(int argc, char** argv);

}  // namespace hpa
