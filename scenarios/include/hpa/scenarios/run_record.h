#pragma once
// DIR/run.json: what a run directory was run from (the scenario's text as it was, the sets and
// overrides applied, the params flown), so the run can be rebuilt later, e.g. by `hpa replay`,
// without the files it came from having to stay unchanged.

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "hpa/models/params.h"
#include "hpa/scenarios/scenario.h"

namespace hpa {

/// The inputs of one run.
struct RunRecord {
  std::string scenario_file;  // where the scenario came from (relative paths in it resolve here)
  std::string scenario_text;  // its text when the run started
  std::vector<ScenarioSet> sets;
  std::optional<unsigned long> seed;  // overrides the file's (--seed, a sweep's draw)
  std::string camera;                 // overrides estimation.camera ("" none)
  std::string controller;             // overrides controller.type ("" none)
  Params params;                      // the params file's values (before the scenario's params:)
};

/// Writes DIR/run.json; throws OutputError if it cannot.
void WriteRunRecord(const std::string& dir, const RunRecord& record);

/// Reads DIR/run.json; throws InputError naming the file and what is missing or malformed.
RunRecord ReadRunRecord(const std::string& dir);

/// The scenario a record describes (its sets and overrides applied).
Scenario ScenarioOf(const RunRecord& record);

}  // namespace hpa
