// Sweep summaries: crash rates with Wilson intervals per controller and per bin of the main
// varied quantity, quantiles of the tracking metrics, the worst runs with replay commands.

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
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

// A grid variable that splits the groups besides the controller, with its values in the sweep
// file's order.
struct GridFactor {
  std::string path;
  std::string name;  // in panel titles: the path's last part, or the whole path if not unique
  std::vector<std::string> values;
};

// A group's place in the grid: its controller and its value of each grid factor.
struct GroupPlace {
  std::string controller;
  std::vector<std::string> values;  // one per SummaryTable::factors entry
};

// How a summary groups and bins a sweep's runs, and the tallies of each group and bin.
struct SummaryTable {
  std::set<std::string> grid_keys;  // grid variables that split the groups, besides the controller
  std::vector<GridFactor> factors;  // the same, in the sweep file's order
  std::vector<std::string> controllers;         // every controller that flew, sorted
  std::map<std::string, GroupPlace> place;      // each group's controller and grid values
  std::string main_path;                        // the main varied quantity ("" when none)
  std::string main_label;                       // its label (its `label:`, else its path)
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

// A run's value of a vary path as its record spells it ("" when it has none).
std::string ValueOf(const Record& r, const std::string& path) {
  for (const auto& [p, value] : r.values) {
    if (p == path) return value;
  }
  return "";
}

// The grid variables besides the controller in the sweep file's order, each with its values in
// the file's order (then any value only the records hold) and its short name.
std::vector<GridFactor> GridFactors(const std::vector<Record>& records, const SweepSpec* spec,
                                    const std::set<std::string>& grid_keys) {
  std::vector<GridFactor> factors;
  if (spec == nullptr) return factors;
  for (const VarySpec& v : spec->vary) {
    if (!grid_keys.count(v.path)) continue;
    GridFactor f{v.path, v.path.substr(v.path.rfind('.') + 1), v.values};
    for (const Record& r : records) {
      const std::string value = ValueOf(r, v.path);
      if (std::find(f.values.begin(), f.values.end(), value) == f.values.end())
        f.values.push_back(value);
    }
    factors.push_back(std::move(f));
  }
  for (GridFactor& f : factors) {
    for (const GridFactor& other : factors) {
      if (&other != &f && other.path.substr(other.path.rfind('.') + 1) == f.name) f.name = f.path;
    }
  }
  return factors;
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
  t.factors = GridFactors(records, spec, t.grid_keys);
  std::set<std::string> controllers;
  for (const Record& r : records) {
    const std::string group = GroupOf(r, t.grid_keys);
    t.groups.insert(group);
    controllers.insert(r.controller);
    GroupPlace& place = t.place[group];
    place.controller = r.controller;
    place.values.clear();
    for (const GridFactor& f : t.factors) place.values.push_back(ValueOf(r, f.path));
  }
  t.controllers.assign(controllers.begin(), controllers.end());
  for (const auto& c : t.groups) t.per_bin[c].resize(t.bins.size());
  for (const Record& r : records) {
    const std::string group = GroupOf(r, t.grid_keys);
    const int bin = BinOf(t.bins, MainValue(r, t.main_path));
    for (Cell* cell : {&t.total[group], &t.per_bin[group][bin]}) AddRun(r, cell);
  }
  return t;
}

// Adds one cell's tallies to another's (bins merged into one row).
void AddCell(const Cell& from, Cell* to) {
  to->n += from.n;
  to->crashes += from.crashes;
  to->errors += from.errors;
  to->expect_failures += from.expect_failures;
  to->rmse.insert(to->rmse.end(), from.rmse.begin(), from.rmse.end());
  to->dev.insert(to->dev.end(), from.dev.begin(), from.dev.end());
  to->solve.insert(to->solve.end(), from.solve.begin(), from.solve.end());
}

// The grid cells of a sweep with two or more grid factors that hold runs, each as its value of
// every factor, in the layout's order: the third and later factors outermost, then the first
// factor's values, the second's innermost (a row of panels or of a table).
std::vector<std::vector<std::string>> GridCells(const SummaryTable& t) {
  std::vector<std::vector<std::string>> cells;
  const size_t k = t.factors.size();
  for (const GridFactor& f : t.factors) {
    if (f.values.empty()) return cells;
  }
  std::vector<size_t> order;  // factors from the outermost to the innermost
  for (size_t i = 2; i < k; ++i) order.push_back(i);
  order.push_back(0);
  order.push_back(1);
  std::vector<size_t> index(k, 0);
  for (;;) {
    std::vector<std::string> values(k);
    for (size_t i = 0; i < k; ++i) values[i] = t.factors[i].values[index[i]];
    for (const auto& [group, place] : t.place) {
      if (place.values == values) {
        cells.push_back(values);
        break;
      }
    }
    int pos = static_cast<int>(order.size()) - 1;  // count on, the innermost factor first
    for (; pos >= 0; --pos) {
      const size_t f = order[static_cast<size_t>(pos)];
      if (++index[f] < t.factors[f].values.size()) break;
      index[f] = 0;
    }
    if (pos < 0) return cells;
  }
}

// The group of a controller in a grid cell (null when no run of it lies there).
const std::string* GroupAt(const SummaryTable& t, const std::string& controller,
                           const std::vector<std::string>& values) {
  for (const auto& [group, place] : t.place) {
    if (place.controller == controller && place.values == values) return &group;
  }
  return nullptr;
}

// "name=value, name=value" of the factors from `first` on: a panel's title, a table's heading.
std::string CellTitle(const SummaryTable& t, const std::vector<std::string>& values,
                      size_t first = 0) {
  std::string title;
  for (size_t i = first; i < t.factors.size(); ++i) {
    title += (title.empty() ? "" : ", ") + t.factors[i].name + "=" + values[i];
  }
  return title;
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

// A cell of summary.md's rate tables: crashes/runs [95 % Wilson interval] and expect failures.
std::string RateText(const Cell& cell) {
  const auto ci = Wilson(cell.crashes, cell.n);
  return std::to_string(cell.crashes) + "/" + std::to_string(cell.n) + " [" + Fixed(ci.first, 2) +
         ", " + Fixed(ci.second, 2) + "] (expect failed " + std::to_string(cell.expect_failures) +
         ")";
}

// summary.md with two or more grid factors: one table per controller (and per combination of
// the third and later factors), rows the first factor's values, columns the second's, each cell
// the crash rate of that group's runs.
void GridTablesMarkdown(const SummaryTable& t, std::ostringstream& md) {
  const GridFactor &rows = t.factors[0], &cols = t.factors[1];
  md << "\n## Crash rate per grid cell (and expect-failure count)\n\nOne table per controller"
     << (t.factors.size() > 2 ? " and combination of the further grid variables" : "") << ": rows `"
     << rows.path << "`, columns `" << cols.path << "`; crashes/runs [95% Wilson CI].\n";
  // the combinations of the third and later factors, in the layout's order
  std::vector<std::vector<std::string>> blocks;
  for (const auto& cell : GridCells(t)) {
    const std::vector<std::string> rest(cell.begin() + 2, cell.end());
    if (std::find(blocks.begin(), blocks.end(), rest) == blocks.end()) blocks.push_back(rest);
  }
  for (const std::string& controller : t.controllers) {
    for (const auto& rest : blocks) {
      std::vector<std::string> values = {"", ""};
      values.insert(values.end(), rest.begin(), rest.end());
      const std::string further = CellTitle(t, values, 2);
      md << "\n### " << controller << (further.empty() ? "" : ", " + further) << "\n\n| "
         << rows.name << " \\ " << cols.name << " |";
      for (const std::string& c : cols.values) md << " " << c << " |";
      md << "\n|---|";
      for (size_t i = 0; i < cols.values.size(); ++i) md << "---|";
      md << "\n";
      for (const std::string& r : rows.values) {
        values[0] = r;
        md << "| " << r << " |";
        for (const std::string& c : cols.values) {
          values[1] = c;
          const std::string* group = GroupAt(t, controller, values);
          md << " " << (group != nullptr ? RateText(t.total.at(*group)) : "-") << " |";
        }
        md << "\n";
      }
    }
  }
}

// summary.md's crash rate per bin of the main varied quantity with two or more grid factors:
// one column per controller, its grid cells pooled (every cell sees the same draws); bins are
// merged with the next until each controller's column holds at least two runs, so no row rests
// on a single run.
void PooledBinTableMarkdown(const SummaryTable& t, std::ostringstream& md) {
  std::map<std::string, std::vector<Cell>> pooled;  // controller -> bins
  for (const std::string& c : t.controllers) pooled[c].resize(t.bins.size());
  for (const auto& [group, place] : t.place) {
    for (size_t b = 0; b < t.bins.size(); ++b)
      AddCell(t.per_bin.at(group)[b], &pooled[place.controller][b]);
  }
  // rows of merged bins: [first bin, last bin] and each controller's tallies
  struct Row {
    size_t first = 0, last = 0;
    std::map<std::string, Cell> cells;
  };
  std::vector<Row> rows;
  Row pending;
  bool open = false;
  for (size_t b = 0; b < t.bins.size(); ++b) {
    if (!open) pending = Row{b, b, {}};
    open = true;
    pending.last = b;
    bool enough = true;
    for (const std::string& c : t.controllers) {
      AddCell(pooled[c][b], &pending.cells[c]);
      int total = 0;  // a controller with fewer than two runs in all does not hold rows open
      for (const Cell& cell : pooled[c]) total += cell.n;
      if (total >= 2 && pending.cells[c].n < 2) enough = false;
    }
    if (enough) {
      rows.push_back(pending);
      open = false;
    }
  }
  if (open && !rows.empty()) {  // the last bins join the row before them
    rows.back().last = pending.last;
    for (const auto& [c, cell] : pending.cells) AddCell(cell, &rows.back().cells[c]);
  } else if (open) {
    rows.push_back(pending);
  }
  md << "\n## Crash rate (and expect-failure count) against " << t.main_label << " (`"
     << t.main_path
     << "`), each controller's grid cells pooled\n\nBins holding fewer than two "
        "runs of a controller are merged with the next.\n\n| bin |";
  for (const std::string& c : t.controllers) md << " " << c << " |";
  md << "\n|---|";
  for (size_t i = 0; i < t.controllers.size(); ++i) md << "---|";
  md << "\n";
  for (const Row& row : rows) {
    const double lo = t.bins[row.first].first, hi = t.bins[row.last].second;
    md << "| " << Fixed(lo) << (lo == hi ? "" : " - " + Fixed(hi)) << " |";
    for (const std::string& c : t.controllers) md << " " << RateText(row.cells.at(c)) << " |";
    md << "\n";
  }
}

// summary.md's crash rate (and expect-failure count) of each group per bin of the main varied
// quantity; with two or more grid factors the grid tables and the pooled bins instead; nothing
// when no quantity is varied (and fewer than two grid factors).
void BinTableMarkdown(const SummaryTable& t, std::ostringstream& md) {
  if (t.factors.size() >= 2) {
    GridTablesMarkdown(t, md);
    if (!t.main_path.empty()) PooledBinTableMarkdown(t, md);
    return;
  }
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
    for (const auto& c : t.groups) md << " " << RateText(t.per_bin.at(c)[b]) << " |";
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
// (thin); lines join neighbouring bins only, so an empty bin breaks them. The CSV names the
// series `name`, `name (expect-failure rate)` and `name (95% CI)`.
void DrawGroupRates(Figure* fig, PlotPanel* p, const std::vector<Cell>& cells,
                    const std::vector<std::pair<double, double>>& bins, const cv::Scalar& colour,
                    const std::string& name) {
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
    fig->series.back().name = name + " (expect-failure rate)";
    p->Line(sx, sy, colour, 2);
    fig->series.back().name = name;
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
  fig->series.back().name = name + " (95% CI)";
}

// The x range of the crash-rate plots: the main varied quantity's bins with a 5 % margin.
void SetRateRange(const SummaryTable& t, PlotPanel* p) {
  double x0 = t.bins.front().first, x1 = t.bins.back().second;
  if (x1 <= x0) x1 = x0 + 1;
  const double pad = 0.05 * (x1 - x0);
  p->SetRange(x0 - pad, x1 + pad, -0.02, 1.02);
}

// Writes crash_rate.png with two or more grid factors: small multiples, one panel per grid
// cell (rows: the first factor's values, and the combinations of the third and later factors;
// columns: the second factor's values, wrapped past kMaxColumns), one colour per controller in
// every panel, one legend above the panels. At most kMaxPanels panels are drawn (the figure
// stays a few megapixels); the header says when cells are left out.
void WriteCrashRatePanels(const SummaryTable& t, const std::string& dir) {
  constexpr size_t kMaxColumns = 6, kMaxPanels = 96;
  constexpr int kPanelHeight_px = 260, kMinPanelWidth_px = 400;
  const std::vector<std::vector<std::string>> cells = GridCells(t);
  const size_t drawn = std::min(cells.size(), kMaxPanels);
  const size_t columns = std::max<size_t>(
      1, std::min({t.factors[1].values.size(), kMaxColumns, std::max<size_t>(drawn, 1)}));
  // wide enough for the longest title (drawn 100 px into the plot, which starts 70 px in)
  int panel_width_px = kMinPanelWidth_px;
  for (size_t i = 0; i < drawn; ++i) {
    int baseline = 0;
    const int title_px =
        cv::getTextSize(CellTitle(t, cells[i]), cv::FONT_HERSHEY_SIMPLEX, 0.55, 1, &baseline).width;
    panel_width_px = std::max(panel_width_px, 170 + title_px + 30);
  }
  const int width_px = static_cast<int>(columns) * panel_width_px;
  // header: what is drawn, the panels' layout, then the shared legend
  std::vector<std::pair<std::string, cv::Scalar>> legend;
  for (size_t k = 0; k < t.controllers.size(); ++k) {
    legend.emplace_back(t.controllers[k], SeriesColour(static_cast<int>(k)));
  }
  std::string layout = "one panel per grid cell: rows " + t.factors[0].path;
  for (size_t i = 2; i < t.factors.size(); ++i) layout += " (within " + t.factors[i].path + ")";
  layout += ", columns " + t.factors[1].path;
  if (drawn < cells.size()) {
    layout += "; the first " + std::to_string(drawn) + " of " + std::to_string(cells.size()) +
              " cells (summary.json has all)";
  }
  // the legend's height is known once drawn: measure it on a scratch figure of the same width
  Figure scratch(width_px, 200);
  const int legend_px = scratch.Legend(cv::Point(10, 0), legend);
  const int header_px = 50 + legend_px;
  const int rows = static_cast<int>((drawn + columns - 1) / columns);
  Figure fig(width_px, header_px + std::max(rows, 1) * kPanelHeight_px);
  fig.Caption(
      cv::Point(10, 20),
      "crash rate (thick, 95% Wilson CI) and expect-failure rate (thin) against " + t.main_label,
      0.55);
  fig.Caption(cv::Point(10, 42), layout, 0.45);
  for (size_t i = 0; i < drawn; ++i) {
    const cv::Rect area(static_cast<int>(i % columns) * panel_width_px,
                        header_px + static_cast<int>(i / columns) * kPanelHeight_px, panel_width_px,
                        kPanelHeight_px);
    PlotPanel p(&fig, area, CellTitle(t, cells[i]), t.main_label, "rate [fraction]");
    SetRateRange(t, &p);
    p.DrawAxes();
    for (size_t k = 0; k < t.controllers.size(); ++k) {
      const cv::Scalar colour = SeriesColour(static_cast<int>(k));
      const std::string* group = GroupAt(t, t.controllers[k], cells[i]);
      if (group != nullptr) {
        DrawGroupRates(&fig, &p, t.per_bin.at(*group), t.bins, colour, t.controllers[k]);
      } else {
        p.Line({}, {}, colour);  // keeps the controller's dash where it has no runs
      }
    }
  }
  fig.Legend(cv::Point(10, 50), legend);
  fig.Write(dir + "/crash_rate", PlotFormat::kPng);
}

// Writes crash_rate.png: each group's crash rate against the main varied quantity (small
// multiples with two or more grid factors); nothing when no quantity is varied.
void WriteCrashRatePlot(const SummaryTable& t, const std::string& dir) {
  if (t.main_path.empty()) return;
  if (t.factors.size() >= 2) return WriteCrashRatePanels(t, dir);
  Figure fig(1000, 600);
  PlotPanel p(&fig, cv::Rect(0, 0, 1000, 600),
              "crash rate (thick, 95% Wilson CI) and expect-failure rate (thin)", t.main_label,
              "rate [fraction of runs]");
  SetRateRange(t, &p);
  p.DrawAxes();
  std::vector<std::pair<std::string, cv::Scalar>> legend;
  int k = 0;
  for (const auto& c : t.groups) {
    DrawGroupRates(&fig, &p, t.per_bin.at(c), t.bins, SeriesColour(k), c);
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
