// How a sweep's summary groups and bins its runs (sweep_summary_table.h): the main varied quantity
// and its bins, the grid factors, each group's and each bin's tallies, and the grid layout of a
// sweep with two or more grid factors.

#include "harness/sweeps/src/sweep_summary_table.h"

#include <algorithm>
#include <cstddef>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "harness/sweeps/src/sweep_internal.h"

namespace hpa::sweep {

// A run's group: its controller and its values of the grid variables.
std::string GroupOf(const Record& r, const std::set<std::string>& grid_keys) {
  std::string group = r.controller;
  for (const auto& [path, value] : r.values) {
    if (grid_keys.count(path)) group += ", " + path + "=" + value;
  }
  return group;
}

namespace {

// A run's value of the main varied quantity (0 when it has none).
double MainValue(const Record& r, const std::string& main_path) {
  for (const auto& [path, value] : r.values) {
    double v;
    if (path == main_path && IsNumber(value, &v)) return v;
  }
  return 0.0;
}

// The main varied quantity: the first numeric vary path that is neither the controller type
// nor one of `not_main` (the grid variables, the command line's sets) ("" when there is none).
std::string MainPath(const std::vector<Record>& records, const std::set<std::string>& not_main) {
  std::string main_path;
  for (const Record& r : records) {
    for (const auto& [path, value] : r.values) {
      if (path != "controller.type" && !not_main.count(path) && IsNumber(value) &&
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

}  // namespace

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
  std::set<std::string> not_main = t.grid_keys;
  if (spec != nullptr) {
    for (const auto& [key, value] : spec->sets) not_main.insert(key);
  }
  t.main_path = MainPath(records, not_main);
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
std::string CellTitle(const SummaryTable& t, const std::vector<std::string>& values, size_t first) {
  std::string title;
  for (size_t i = first; i < t.factors.size(); ++i) {
    title += (title.empty() ? "" : ", ") + t.factors[i].name + "=" + values[i];
  }
  return title;
}

}  // namespace hpa::sweep
