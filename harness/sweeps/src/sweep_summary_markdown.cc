// A sweep's summary.md: the table of each group's counts, rates and quantiles, the crash rate per
// bin of the main varied quantity (with two or more grid factors: a table per controller over
// the grid, and the bins pooled over each controller's grid cells), the worst runs and the
// outlier runs, each with the command that replays it.

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "hpa/models/file_io.h"
#include "hpa/scenarios/metrics.h"
#include "harness/sweeps/src/sweep_internal.h"
#include "harness/sweeps/src/sweep_summary_table.h"

namespace hpa::sweep {
namespace {

std::string Fixed(double v, int decimals = 3) {
  if (!std::isfinite(v)) return "-";
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals) << v;
  return out.str();
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

}  // namespace

// Writes summary.md: the group table, the crash rate per bin, the worst and the outlier runs.
void WriteSummaryMarkdown(const std::vector<Record>& records, const SummaryTable& t,
                          const std::vector<Outlier>& outliers, const std::string& dir) {
  std::ostringstream md;
  md << "# Sweep summary\n\n" << records.size() << " runs";
  if (!records.empty())
    md << " of `" << records.front().sweep_file << "` (base `" << records.front().base << "`)";
  md << ". Crash rates with 95 % Wilson intervals; RMSE is the norm of the per-axis payload RMSE "
        "over runs that did not crash.\n\n";
  std::set<std::string> stacks;
  for (const Record& r : records) {
    if (!r.flight_stack.empty()) stacks.insert("`" + r.flight_stack + "`");
  }
  if (!stacks.empty()) {
    std::string listed;
    for (const std::string& s : stacks) listed += (listed.empty() ? "" : ", ") + s;
    md << "Flown by the flight stack" << (stacks.size() > 1 ? "s " : " ") << listed
       << ", started once per run; a run's controller is the name the stack gave in its hello "
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

}  // namespace hpa::sweep
