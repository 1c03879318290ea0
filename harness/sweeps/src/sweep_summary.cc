// Sweep summaries: crash rates with Wilson intervals per controller and per bin of the main
// varied quantity, quantiles of the tracking metrics, the worst runs with replay commands.
// WriteSummary tabulates the runs (sweep_summary_table.cc) and writes summary.json
// (sweep_summary_json.cc), summary.md (sweep_summary_markdown.cc) and crash_rate.png
// (sweep_crash_rate_plot.cc). The statistics they rest on are here: Wilson intervals, the bins of
// a varied quantity and the outlier runs.

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "hpa/scenarios/metrics.h"
#include "harness/sweeps/src/sweep_internal.h"
#include "harness/sweeps/src/sweep_summary_table.h"

namespace hpa::sweep {

std::pair<double, double> Wilson(int k, int n) {
  if (n == 0) return {0.0, 1.0};
  const double z = 1.959963984540054, p = static_cast<double>(k) / n;
  const double denom = 1 + z * z / n;
  const double centre = (p + z * z / (2 * n)) / denom;
  const double half = z * std::sqrt(p * (1 - p) / n + z * z / (4.0 * n * n)) / denom;
  return {std::max(0.0, centre - half), std::min(1.0, centre + half)};
}

std::vector<std::pair<double, double>> MakeBins(const std::vector<double>& values) {
  const std::set<double> distinct(values.begin(), values.end());
  std::vector<std::pair<double, double>> bins;
  if (distinct.size() <= 8) {
    for (double v : distinct) bins.emplace_back(v, v);
  } else {
    const double lo = *distinct.begin(), hi = *distinct.rbegin();
    for (int i = 0; i < 6; ++i) {
      bins.emplace_back(lo + (hi - lo) * i / 6.0, lo + (hi - lo) * (i + 1) / 6.0);
    }
  }
  return bins;
}

int BinOf(const std::vector<std::pair<double, double>>& bins, double v) {
  for (size_t i = 0; i < bins.size(); ++i) {
    if (v >= bins[i].first - 1e-12 && v <= bins[i].second + 1e-12) return static_cast<int>(i);
  }
  return static_cast<int>(bins.size()) - 1;
}

void WriteSummary(const std::vector<Record>& records, const std::string& dir,
                  const SweepSpec* spec) {
  const SummaryTable table = Tabulate(records, spec);
  const std::vector<Outlier> outliers = FindOutliers(records, table.grid_keys);
  WriteSummaryJson(records, table, outliers, dir);
  WriteSummaryMarkdown(records, table, outliers, dir);
  WriteCrashRatePlot(table, dir);
}

std::vector<Outlier> FindOutliers(const std::vector<Record>& records,
                                  const std::set<std::string>& grid_keys) {
  struct Rule {
    const char* metric;
    double (*value)(const Record&);
    int sign;      // -1: low is bad, +1: high is bad
    double floor;  // smallest difference from the median worth listing
  };
  const Rule rules[] = {
      {"mode_accuracy", [](const Record& r) { return r.mode_accuracy; }, -1, 0.05},
      {"payload_in_fov_fraction", [](const Record& r) { return r.payload_in_fov; }, -1, 0.05},
      {"estimator_restarts", [](const Record& r) { return r.estimator_restarts; }, +1, 2.0},
  };
  // within a grid cell: a cell with 30 times the detector noise is not judged by the others
  std::map<std::string, std::vector<const Record*>> by_group;
  for (const Record& r : records) {
    if (!r.error) by_group[GroupOf(r, grid_keys)].push_back(&r);
  }
  std::vector<Outlier> out;
  for (const auto& [group, runs] : by_group) {
    for (const Rule& rule : rules) {
      std::vector<double> values;
      for (const Record* r : runs) {
        if (std::isfinite(rule.value(*r))) values.push_back(rule.value(*r));
      }
      if (values.size() < 3) continue;
      const double median = Quantile(values, 0.5);
      std::vector<double> deviations;
      for (double v : values) deviations.push_back(std::fabs(v - median));
      const double spread = 5.0 * 1.4826 * Quantile(deviations, 0.5);
      for (const Record* r : runs) {
        const double v = rule.value(*r);
        const double beyond = rule.sign * (v - median);
        if (std::isfinite(v) && beyond > spread && beyond > rule.floor) {
          out.push_back({r, rule.metric, v, median});
        }
      }
    }
  }
  return out;
}

}  // namespace hpa::sweep
