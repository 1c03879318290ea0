// A sweep's summary.json: how the runs are grouped, each group's counts, crash rate with its
// Wilson interval, quantiles and per-bin crash rates, and the outlier runs with their replay
// commands (and ReplayCommand, which summary.md's lists use too).

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "hpa/models/file_io.h"
#include "hpa/scenarios/metrics.h"
#include "harness/sweeps/src/sweep_internal.h"
#include "harness/sweeps/src/sweep_summary_table.h"

namespace hpa::sweep {
namespace {

using Json = nlohmann::ordered_json;

// A number for summary.json; non-finite values (e.g. quantiles of no run) are null.
Json Num(double v) { return std::isfinite(v) ? Json(v) : Json(); }

// `text` as one shell word: in single quotes, each quote inside closed, escaped and reopened.
std::string ShellQuoted(const std::string& text) {
  std::string quoted = "'";
  for (const char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

}  // namespace

// The command that replays a run exactly (with the flight stack that flew it).
std::string ReplayCommand(const Record& r) {
  std::string command = "hpa run " + r.base + " --seed " + std::to_string(r.seed);
  for (const auto& [path, value] : r.values) {
    // the stack factor's value names the stack, whose command follows
    if (path != kStackFactor) command += " --set " + path + "=" + value;
  }
  if (!r.flight_stack.empty()) command += " --flight-stack " + ShellQuoted(r.flight_stack);
  return command;
}

namespace {

// One group's entry of summary.json: its counts, crash rate, quantiles and per-bin crash rates.
Json GroupJson(const Cell& t, const std::vector<Cell>& cells,
               const std::vector<std::pair<double, double>>& bins) {
  const auto ci = Wilson(t.crashes, t.n);
  Json entry = {{"runs", t.n},
                {"errors", t.errors},
                {"crashes", t.crashes},
                {"crash_rate", t.n ? Num(static_cast<double>(t.crashes) / t.n) : Json()},
                {"crash_rate_ci95", {Num(ci.first), Num(ci.second)}},
                {"expect_failures", t.expect_failures},
                {"payload_rmse_norm_m",
                 {{"median", Num(Quantile(t.rmse, 0.5))}, {"p90", Num(Quantile(t.rmse, 0.9))}}},
                {"quad_deviation_max_m",
                 {{"median", Num(Quantile(t.dev, 0.5))}, {"p90", Num(Quantile(t.dev, 0.9))}}},
                {"mpc_solve_median_ms",
                 {{"median", Num(Quantile(t.solve, 0.5))}, {"p99", Num(Quantile(t.solve, 0.99))}}},
                {"bins", Json::array()}};
  for (size_t b = 0; b < bins.size(); ++b) {
    const Cell& cell = cells[b];
    const auto bci = Wilson(cell.crashes, cell.n);
    entry["bins"].push_back(
        {{"lo", Num(bins[b].first)},
         {"hi", Num(bins[b].second)},
         {"runs", cell.n},
         {"crashes", cell.crashes},
         {"crash_rate", cell.n ? Num(static_cast<double>(cell.crashes) / cell.n) : Json()},
         {"ci95", {Num(bci.first), Num(bci.second)}},
         {"expect_failures", cell.expect_failures}});
  }
  return entry;
}

}  // namespace

// Writes summary.json: how the runs are grouped, each group's entry and the outlier runs.
void WriteSummaryJson(const std::vector<Record>& records, const SummaryTable& t,
                      const std::vector<Outlier>& outliers, const std::string& dir) {
  Json summary;
  summary["runs"] = records.size();
  summary["main_varied"] = t.main_path;
  summary["main_varied_label"] = t.main_label;
  summary["grouped_by"] = Json::array({"controller.type"});
  for (const std::string& key : t.grid_keys) summary["grouped_by"].push_back(key);
  summary["controllers"] = Json::object();
  for (const auto& c : t.groups) {
    summary["controllers"][c] = GroupJson(t.total.at(c), t.per_bin.at(c), t.bins);
  }
  summary["outliers"] = Json::array();
  for (const Outlier& o : outliers) {
    summary["outliers"].push_back({{"run", o.record->run},
                                   {"controller", o.record->controller},
                                   {"metric", o.metric},
                                   {"value", Num(o.value)},
                                   {"median", Num(o.median)},
                                   {"replay", ReplayCommand(*o.record)}});
  }
  WriteFileAtomic(dir + "/summary.json", summary.dump(2) + "\n");
}

}  // namespace hpa::sweep
