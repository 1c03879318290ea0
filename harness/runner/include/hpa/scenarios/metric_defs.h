#pragma once
// The one table of scalar metrics read from metrics.json (name, where it lives, unit, which way
// is better, smallest effect that matters, how to read it): `hpa compare`, `hpa sweep-diff`,
// sweep summaries and records, expect keys (which bound a metric of this table) and
// `hpa schema metrics` all read it. A new metric is its field in metrics.cc and one line in
// metric_defs.cc.

#include <cmath>
#include <optional>
#include <string>
#include <vector>

namespace hpa {

/// Which direction of a metric is better.
enum class Better { kLower, kHigher, kNeither };

/// How a metric's value is read at its JSON path.
enum class MetricRead {
  kNumber,      // the number there (null or absent: not measured)
  kNorm,        // the Euclidean norm of the 3-vector there
  kFlag,        // a boolean: 1 true, 0 false
  kIfRetauted,  // the number there, only when the run had a re-taut (retaut.count > 0)
  kLargest,     // through a list on the path (a team's vehicles), the largest of its entries'
};

/// One scalar metric.
struct MetricDef {
  std::string name;       // as tools name it (sweep-diff rows, outliers, schema)
  std::string json_path;  // where metrics.json holds it, dotted ("retaut.quad_vz_min_mps")
  MetricRead read = MetricRead::kNumber;
  std::string unit;  // "m", "s", "fraction", "0/1", ...
  Better better = Better::kNeither;
  double min_effect = 0.0;  // smallest difference that matters, in `unit` (sweep-diff power)
  bool timing = false;      // measures the machine, not the controller
  bool compared = false;    // sweep-diff pairs it between two sweeps
  std::string label;        // short table label with its unit ("payload RMSE norm [m]");
                            // empty: not a row of `hpa compare`
  std::string description;  // how to read it, one line
};

/// Every metric, in table order.
const std::vector<MetricDef>& MetricDefs();

/// The metric named `name`, or nullptr.
const MetricDef* FindMetric(const std::string& name);

/// The metric named `name`; throws std::logic_error for an unregistered name (a tool asking for
/// a metric that the table does not declare is a programming error).
const MetricDef& GetMetric(const std::string& name);

/// Reads `def` from one run's metrics.json object (any nlohmann JSON type); nullopt where the
/// run did not measure it (null, absent, not a number, or no re-taut for kIfRetauted).
template <typename Json>
std::optional<double> ReadMetric(const MetricDef& def, const Json& metrics) {
  const Json* node = &metrics;
  for (size_t start = 0; start <= def.json_path.size();) {
    if (def.read == MetricRead::kLargest && node->is_array()) {
      // the rest of the path in every entry of the list, the largest value measured
      MetricDef rest = def;
      rest.json_path = def.json_path.substr(start);
      rest.read = MetricRead::kNumber;
      std::optional<double> largest;
      for (const auto& entry : *node) {
        const std::optional<double> v = ReadMetric(rest, entry);
        if (v && (!largest || *v > *largest)) largest = v;
      }
      return largest;
    }
    const size_t dot = std::min(def.json_path.find('.', start), def.json_path.size());
    const std::string key = def.json_path.substr(start, dot - start);
    if (!node->is_object() || !node->contains(key)) return std::nullopt;
    node = &(*node)[key];
    start = dot + 1;
  }
  switch (def.read) {
    case MetricRead::kNumber:
    case MetricRead::kLargest:  // no list on the path: the number there
      break;
    case MetricRead::kNorm: {
      if (!node->is_array() || node->size() != 3) return std::nullopt;
      double sum = 0.0;
      for (const auto& v : *node) {
        if (!v.is_number()) return std::nullopt;
        sum += std::pow(v.template get<double>(), 2);
      }
      return std::sqrt(sum);
    }
    case MetricRead::kFlag:
      if (!node->is_boolean()) return std::nullopt;
      return node->template get<bool>() ? 1.0 : 0.0;
    case MetricRead::kIfRetauted: {
      const auto retaut = metrics.find("retaut");
      if (retaut == metrics.end() || !retaut->is_object() || !(*retaut).contains("count") ||
          !(*retaut)["count"].is_number() || (*retaut)["count"].template get<double>() <= 0) {
        return std::nullopt;
      }
      break;
    }
  }
  if (!node->is_number()) return std::nullopt;
  return node->template get<double>();
}

/// The metric named `name` read from `metrics` (GetMetric + ReadMetric).
template <typename Json>
std::optional<double> ReadMetric(const std::string& name, const Json& metrics) {
  return ReadMetric(GetMetric(name), metrics);
}

}  // namespace hpa
