// Sweep summaries: crash rates with Wilson intervals per controller and per bin of the main
// varied quantity, quantiles of the tracking metrics, the worst runs with replay commands.

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <sstream>

#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "hpa/scenarios/metrics.h"
#include "hpa/scenarios/plot_canvas.h"
#include "scenarios/src/tools/sweep/sweep_internal.h"

namespace hpa::sweep {
namespace {

using Json = nlohmann::ordered_json;

std::string Fixed(double v, int decimals = 3) {
  if (!std::isfinite(v)) return "-";
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals) << v;
  return out.str();
}

}  // namespace

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

namespace {

// Tallies of the runs of one group, or of one group's bin of the main varied quantity.
struct Cell {
  int n = 0, crashes = 0, errors = 0, expect_failures = 0;
  std::vector<double> rmse, dev, solve;
};

// How a summary groups and bins a sweep's runs, and the tallies of each group and bin.
struct SummaryTable {
  std::set<std::string> grid_keys;  // grid variables that split the groups, besides the controller
  std::string main_path;            // the main varied quantity ("" when none)
  std::string main_label;           // its label (its `label:`, else its path)
  std::vector<std::pair<double, double>> bins;  // over the main varied quantity
  std::set<std::string> groups;                 // controller and grid values
  std::map<std::string, Cell> total;
  std::map<std::string, std::vector<Cell>> per_bin;
};

// A run's group: its controller and its values of the grid variables.
std::string GroupOf(const Record& r, const std::set<std::string>& grid_keys) {
  std::string group = r.controller;
  for (const auto& [path, value] : r.values) {
    if (grid_keys.count(path)) group += ", " + path + "=" + value;
  }
  return group;
}

// A run's value of the main varied quantity (0 when it has none).
double MainValue(const Record& r, const std::string& main_path) {
  for (const auto& [path, value] : r.values) {
    double v;
    if (path == main_path && IsNumber(value, &v)) return v;
  }
  return 0.0;
}

// The main varied quantity: the first numeric vary path that is neither the controller type
// nor a grid variable ("" when there is none).
std::string MainPath(const std::vector<Record>& records, const std::set<std::string>& grid_keys) {
  std::string main_path;
  for (const Record& r : records) {
    for (const auto& [path, value] : r.values) {
      if (path != "controller.type" && !grid_keys.count(path) && IsNumber(value) &&
          main_path.empty()) {
        main_path = path;
      }
    }
    if (!main_path.empty()) break;
  }
  return main_path;
}

// Bins over the main varied quantity: a uniform draw gets six bins over its declared range, not
// the range the draws happened to cover; anything else gets MakeBins over the values.
std::vector<std::pair<double, double>> MainBins(const std::vector<Record>& records,
                                                const std::string& main_path,
                                                const VarySpec* main_vary) {
  std::vector<double> main_values;
  for (const Record& r : records) main_values.push_back(MainValue(r, main_path));
  std::vector<std::pair<double, double>> bins = MakeBins(main_values);
  if (main_vary != nullptr && main_vary->kind == VarySpec::Kind::kUniform &&
      main_vary->b > main_vary->a && bins.size() > 1 && bins.front().first != bins.front().second) {
    bins.clear();
    for (int i = 0; i < 6; ++i) {
      bins.emplace_back(main_vary->a + (main_vary->b - main_vary->a) * i / 6.0,
                        main_vary->a + (main_vary->b - main_vary->a) * (i + 1) / 6.0);
    }
  }
  return bins;
}

// Adds one run to a cell's tallies (an error counts apart; RMSE only of runs that did not crash).
void AddRun(const Record& r, Cell* cell) {
  if (r.error) {
    ++cell->errors;
    return;
  }
  ++cell->n;
  if (r.crashed) ++cell->crashes;
  if (r.expect_failed) ++cell->expect_failures;
  if (!r.crashed) cell->rmse.push_back(r.payload_rmse_norm_m);
  cell->dev.push_back(r.quad_dev_max_m);
  cell->solve.push_back(r.solve_median_ms);
}

// Groups the runs (grid variables group them, the controller always does), bins the main
// varied quantity and tallies each group and bin.
SummaryTable Tabulate(const std::vector<Record>& records, const SweepSpec* spec) {
  SummaryTable t;
  std::map<std::string, const VarySpec*> vary_of;
  if (spec != nullptr) {
    for (const VarySpec& v : spec->vary) {
      vary_of[v.path] = &v;
      if (v.kind == VarySpec::Kind::kGrid && v.path != "controller.type")
        t.grid_keys.insert(v.path);
    }
  }
  t.main_path = MainPath(records, t.grid_keys);
  const VarySpec* main_vary = vary_of.count(t.main_path) ? vary_of[t.main_path] : nullptr;
  t.main_label = main_vary != nullptr && !main_vary->label.empty() ? main_vary->label : t.main_path;
  t.bins = MainBins(records, t.main_path, main_vary);
  for (const Record& r : records) t.groups.insert(GroupOf(r, t.grid_keys));
  for (const auto& c : t.groups) t.per_bin[c].resize(t.bins.size());
  for (const Record& r : records) {
    const std::string group = GroupOf(r, t.grid_keys);
    const int bin = BinOf(t.bins, MainValue(r, t.main_path));
    for (Cell* cell : {&t.total[group], &t.per_bin[group][bin]}) AddRun(r, cell);
  }
  return t;
}

// A number for summary.json; non-finite values (e.g. quantiles of no run) are null.
Json Num(double v) { return std::isfinite(v) ? Json(v) : Json(); }

// `text` as one shell word: in single quotes, each quote inside closed, escaped and reopened.
std::string ShellQuoted(const std::string& text) {
  std::string quoted = "'";
  for (const char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

// The command that replays a run exactly (with the flight stack that flew it).
std::string ReplayCommand(const Record& r) {
  std::string command = "hpa run " + r.base + " --seed " + std::to_string(r.seed);
  for (const auto& [path, value] : r.values) command += " --set " + path + "=" + value;
  if (!r.flight_stack.empty()) command += " --flight-stack " + ShellQuoted(r.flight_stack);
  return command;
}

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

// summary.md's table of each group's counts, rates with Wilson intervals and quantiles.
void GroupTableMarkdown(const SummaryTable& t, std::ostringstream& md) {
  md << "| controller | runs | errors | crashes | crash rate [95% CI] | expect failures [95% CI] | "
        "payload RMSE median / p90 [m] | quad deviation median / p90 [m] | solve median [ms] "
        "|\n|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& c : t.groups) {
    const Cell& g = t.total.at(c);
    const auto ci = Wilson(g.crashes, g.n);
    md << "| " << c << " | " << g.n << " | " << g.errors << " | " << g.crashes << " | "
       << Fixed(g.n ? 1.0 * g.crashes / g.n : NAN, 3) << " [" << Fixed(ci.first, 3) << ", "
       << Fixed(ci.second, 3) << "] | " << g.expect_failures << "/" << g.n << " ["
       << Fixed(Wilson(g.expect_failures, g.n).first, 3) << ", "
       << Fixed(Wilson(g.expect_failures, g.n).second, 3) << "] | " << Fixed(Quantile(g.rmse, 0.5))
       << " / " << Fixed(Quantile(g.rmse, 0.9)) << " | " << Fixed(Quantile(g.dev, 0.5)) << " / "
       << Fixed(Quantile(g.dev, 0.9)) << " | " << Fixed(Quantile(g.solve, 0.5)) << " |\n";
  }
}

// summary.md's crash rate (and expect-failure count) of each group per bin of the main varied
// quantity; nothing when no quantity is varied.
void BinTableMarkdown(const SummaryTable& t, std::ostringstream& md) {
  if (t.main_path.empty()) return;
  md << "\n## Crash rate (and expect-failure count) against " << t.main_label << " (`"
     << t.main_path << "`)\n\n| bin |";
  for (const auto& c : t.groups) md << " " << c << " |";
  md << "\n|---|";
  for (size_t i = 0; i < t.groups.size(); ++i) md << "---|";
  md << "\n";
  for (size_t b = 0; b < t.bins.size(); ++b) {
    md << "| " << Fixed(t.bins[b].first)
       << (t.bins[b].first == t.bins[b].second ? "" : " - " + Fixed(t.bins[b].second)) << " |";
    for (const auto& c : t.groups) {
      const Cell& cell = t.per_bin.at(c)[b];
      const auto ci = Wilson(cell.crashes, cell.n);
      md << " " << cell.crashes << "/" << cell.n << " [" << Fixed(ci.first, 2) << ", "
         << Fixed(ci.second, 2) << "] (expect failed " << cell.expect_failures << ") |";
    }
    md << "\n";
  }
}

// summary.md's worst runs (errors, crashes, then largest quadrotor deviation), each with the
// command that replays it exactly.
void WorstRunsMarkdown(const std::vector<Record>& records, std::ostringstream& md) {
  std::vector<const Record*> worst;
  for (const Record& r : records) worst.push_back(&r);
  std::sort(worst.begin(), worst.end(), [](const Record* a, const Record* b) {
    if (a->error != b->error) return a->error;
    if (a->crashed != b->crashed) return a->crashed;
    return a->quad_dev_max_m > b->quad_dev_max_m;
  });
  md << "\n## Worst runs (errors, crashes, then largest quadrotor deviation)\n\n";
  for (size_t i = 0; i < std::min<size_t>(8, worst.size()); ++i) {
    const Record& r = *worst[i];
    md << "- run " << r.run << " (" << r.controller << "): "
       << (r.error ? "ERROR " + r.error_text
                   : (r.crashed ? std::string("crashed") : std::string("ok")) +
                         ", quad deviation " + Fixed(r.quad_dev_max_m) + " m")
       << "\n  `" << ReplayCommand(r) << "`\n";
  }
}

// Writes summary.md: the group table, the crash rate per bin, the worst and the outlier runs.
void WriteSummaryMarkdown(const std::vector<Record>& records, const SummaryTable& t,
                          const std::vector<Outlier>& outliers, const std::string& dir) {
  std::ostringstream md;
  md << "# Sweep summary\n\n" << records.size() << " runs";
  if (!records.empty())
    md << " of `" << records.front().sweep_file << "` (base `" << records.front().base << "`)";
  md << ". Crash rates with 95 % Wilson intervals; RMSE is the norm of the per-axis payload RMSE "
        "over runs that did not crash.\n\n";
  if (!records.empty() && !records.front().flight_stack.empty()) {
    md << "Flown by the flight stack `" << records.front().flight_stack
       << "`, started once per run; a run's controller is the name the stack gave in its hello "
          "(`external`: it never did).\n\n";
  }
  GroupTableMarkdown(t, md);
  BinTableMarkdown(t, md);
  WorstRunsMarkdown(records, md);
  md << "\n## Outlier runs (mode accuracy, in view, estimator restarts)\n\n"
     << "A finished run is listed when its mode accuracy or in-view fraction lies below, or its "
        "estimator restarts (metrics.json's estimator.resets + estimator.cable_reinitialisations) "
        "above, the median of its group (controller and grid cell, as in the table above) by more "
        "than 5 scaled MADs and by more than 0.05 (fractions) or 2 (restarts).\n\n";
  if (outliers.empty()) md << "None.\n";
  for (const Outlier& o : outliers) {
    md << "- run " << o.record->run << " (" << o.record->controller << "): " << o.metric << " "
       << Fixed(o.value) << " (median " << Fixed(o.median) << ")\n  `" << ReplayCommand(*o.record)
       << "`\n";
  }
  WriteFileAtomic(dir + "/summary.md", md.str());
}

// Draws one group's crash rate per bin (thick, with its Wilson interval) and expect-failure rate
// (thin); lines join neighbouring bins only, so an empty bin breaks them.
void DrawGroupRates(PlotPanel* p, const std::vector<Cell>& cells,
                    const std::vector<std::pair<double, double>>& bins, const cv::Scalar& colour) {
  std::vector<double> x, y, lo, hi, fail;
  std::vector<bool> segment_break;  // an empty bin lies before this point
  bool gap = false;
  for (size_t b = 0; b < bins.size(); ++b) {
    const Cell& cell = cells[b];
    if (cell.n == 0) {
      gap = true;
      continue;
    }
    segment_break.push_back(gap);
    gap = false;
    const auto ci = Wilson(cell.crashes, cell.n);
    x.push_back(0.5 * (bins[b].first + bins[b].second));
    y.push_back(1.0 * cell.crashes / cell.n);
    lo.push_back(ci.first);
    hi.push_back(ci.second);
    fail.push_back(1.0 * cell.expect_failures / cell.n);
  }
  std::vector<double> sx, sy, sfail;
  const auto flush = [&]() {
    p->Line(sx, sfail, colour, 1);
    p->Line(sx, sy, colour, 2);
    sx.clear();
    sy.clear();
    sfail.clear();
  };
  for (size_t i = 0; i < x.size(); ++i) {
    if (i > 0 && segment_break[i]) flush();
    sx.push_back(x[i]);
    sy.push_back(y[i]);
    sfail.push_back(fail[i]);
  }
  flush();
  p->ErrorBars(x, y, lo, hi, colour);
}

// Writes crash_rate.png: each group's crash rate against the main varied quantity; nothing when
// no quantity is varied.
void WriteCrashRatePlot(const SummaryTable& t, const std::string& dir) {
  if (t.main_path.empty()) return;
  Figure fig(1000, 600);
  PlotPanel p(&fig, cv::Rect(0, 0, 1000, 600),
              "crash rate (thick, 95% Wilson CI) and expect-failure rate (thin)", t.main_label,
              "rate [fraction of runs]");
  double x0 = t.bins.front().first, x1 = t.bins.back().second;
  if (x1 <= x0) x1 = x0 + 1;
  const double pad = 0.05 * (x1 - x0);
  p.SetRange(x0 - pad, x1 + pad, -0.02, 1.02);
  p.DrawAxes();
  std::vector<std::pair<std::string, cv::Scalar>> legend;
  int k = 0;
  for (const auto& c : t.groups) {
    DrawGroupRates(&p, t.per_bin.at(c), t.bins, SeriesColour(k));
    legend.emplace_back(c, SeriesColour(k));
    ++k;
  }
  p.Legend(legend);
  fig.Write(dir + "/crash_rate", PlotFormat::kPng);
}

}  // namespace

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
