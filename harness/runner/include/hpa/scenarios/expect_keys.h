#pragma once
// The one table of `expect:` keys (key, metric, comparison, unit): scenario validation, the
// check after a run, `hpa --help` and `hpa schema` all read it. A new expect key is one entry in
// expect_keys.cc (plus its metric in metric_defs.cc, if that is new), or a RegisterExpectKey call.

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace hpa {

struct Metrics;

/// One expect key.
struct ExpectKey {
  std::string key;              // as written under `expect:`
  std::string metric;           // the metrics.json key it bounds
  std::string comparison;       // how: "metric <= bound", "metric >= bound", "metric == bound"
  std::string unit;             // of the bound
  std::string description;      // one line
  int size = 1;                 // values in the bound: 1, 3 (per axis x, y, z) or 0 (a boolean)
  double min = 0.0, max = 0.0;  // allowed bound values
  bool integer = false;         // the bound is a whole number
  /// Failure messages for `metrics` against `bound` (empty: the bound holds).
  std::function<std::vector<std::string>(const Metrics&, const std::vector<double>&)> check;
};

/// Every expect key, in the order they are checked.
const std::vector<ExpectKey>& ExpectKeys();

/// The key named `key`, or nullptr.
const ExpectKey* FindExpectKey(const std::string& key);

/// Adds an expect key at run time (tests, plugins); throws std::invalid_argument on an empty or
/// duplicate key or a missing check. Its `metric` should name a metric of metric_defs.h.
void RegisterExpectKey(ExpectKey key);

}  // namespace hpa
