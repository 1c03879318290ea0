#pragma once
// How a sweep's summary groups and bins its runs (private to the files of harness/cli/src/
// sweep/ that write the summary): the tallies of each group and bin, the grid layout of a sweep
// with two or more grid factors, and the pieces summary.json, summary.md and crash_rate.png share.
// sweep_summary_table.cc tabulates; sweep_summary_json.cc, sweep_summary_markdown.cc and
// sweep_crash_rate_plot.cc write.

#include <cstddef>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "hpa/scenarios/sweep.h"
#include "harness/sweeps/src/sweep_internal.h"

namespace hpa::sweep {

/// Tallies of the runs of one group, or of one group's bin of the main varied quantity.
struct Cell {
  int n = 0, crashes = 0, errors = 0, expect_failures = 0;
  std::vector<double> rmse, dev, solve;
};

/// A grid variable that splits the groups besides the controller, with its values in the sweep
/// file's order.
struct GridFactor {
  std::string path;
  std::string name;  // in panel titles: the path's last part, or the whole path if not unique
  std::vector<std::string> values;
};

/// A group's place in the grid: its controller and its value of each grid factor.
struct GroupPlace {
  std::string controller;
  std::vector<std::string> values;  // one per SummaryTable::factors entry
};

/// How a summary groups and bins a sweep's runs, and the tallies of each group and bin.
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

/// A run's group: its controller and its values of the grid variables.
std::string GroupOf(const Record& r, const std::set<std::string>& grid_keys);

/// Groups the runs (grid variables group them, the controller always does), bins the main
/// varied quantity and tallies each group and bin.
SummaryTable Tabulate(const std::vector<Record>& records, const SweepSpec* spec);

/// Adds one cell's tallies to another's (bins merged into one row).
void AddCell(const Cell& from, Cell* to);

/// The grid cells of a sweep with two or more grid factors that hold runs, each as its value of
/// every factor, in the layout's order: the third and later factors outermost, then the first
/// factor's values, the second's innermost (a row of panels or of a table).
std::vector<std::vector<std::string>> GridCells(const SummaryTable& t);

/// The group of a controller in a grid cell (null when no run of it lies there).
const std::string* GroupAt(const SummaryTable& t, const std::string& controller,
                           const std::vector<std::string>& values);

/// "name=value, name=value" of the factors from `first` on: a panel's title, a table's heading.
std::string CellTitle(const SummaryTable& t, const std::vector<std::string>& values,
                      size_t first = 0);

/// The command that replays a run exactly (with the flight stack that flew it).
std::string ReplayCommand(const Record& r);

/// Writes summary.json: how the runs are grouped, each group's entry and the outlier runs.
void WriteSummaryJson(const std::vector<Record>& records, const SummaryTable& t,
                      const std::vector<Outlier>& outliers, const std::string& dir);

/// Writes summary.md: the group table, the crash rate per bin, the worst and the outlier runs.
void WriteSummaryMarkdown(const std::vector<Record>& records, const SummaryTable& t,
                          const std::vector<Outlier>& outliers, const std::string& dir);

/// Writes crash_rate.png: each group's crash rate against the main varied quantity (small
/// multiples with two or more grid factors); nothing when no quantity is varied.
void WriteCrashRatePlot(const SummaryTable& t, const std::string& dir);

}  // namespace hpa::sweep
