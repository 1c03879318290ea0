#pragma once
// The runs sweep-diff compares, read from a sweep's runs.jsonl (private to sweep-diff).

#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace hpa::sweep_diff_runs {

/// One runs.jsonl record reduced to what the comparison needs.
struct Run {
  int draw = 0;
  unsigned long seed = 0;
  std::map<std::string, std::string> values;  // varied key -> value as JSON text
  bool ok = false;                            // finished without a run error
  nlohmann::json metrics;                     // null if none
  std::string sweep;
  std::string controller;  // what flew: a controller type or the name a flight stack gave
  std::string inputs_id;   // hash of the sweep and base files the run was flown from
  std::string build;       // the build that flew it (DescribeBuild), "not recorded" if unknown
  std::optional<std::string> basis;  // what its flight code acted on (EstimationBasis)
};

/// The runs of DIR/runs.jsonl, those whose varied key has the value when `where` is KEY=VALUE
/// (numeric values match numerically); an InputError naming the file and line for a record that
/// is none, for no run, or (listing what there is) for a filter no run matches.
std::vector<Run> ReadRuns(const std::string& dir, const std::string& where);

}  // namespace hpa::sweep_diff_runs
