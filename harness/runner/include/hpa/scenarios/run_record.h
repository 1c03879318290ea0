#pragma once
// DIR/run.json: what a run directory was run from (the scenario's text as it was, the sets and
// overrides applied, the params flown, the reference CSV's text), so the run can be rebuilt
// later, e.g. by `hpa replay`, from any working directory and without the files it came from
// having to stay unchanged or even exist.

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
  // a csv reference's file text when the run started (none: not a csv reference); the scenario
  // is rebuilt from it instead of from the file
  std::optional<std::string> reference_csv_text;
};

/// Writes DIR/run.json atomically, completing the record first: scenario_file made absolute and,
/// for a csv reference, the CSV's text kept in reference_csv_text. Throws OutputError if it
/// cannot write, InputError if the record's scenario cannot be loaded.
void WriteRunRecord(const std::string& dir, const RunRecord& record);

/// Reads DIR/run.json (a regular file of bounded size) and checks it: every key present with its
/// type, seed a whole number in [0, 4294967295], camera one of CameraNames(), controller a
/// registered one, and the scenario it describes loadable. Throws InputError naming run.json,
/// the key and what was expected.
RunRecord ReadRunRecord(const std::string& dir);

/// The scenario a record describes (its sets and overrides applied, a csv reference rebuilt from
/// reference_csv_text when the record has it).
Scenario ScenarioOf(const RunRecord& record);

}  // namespace hpa
