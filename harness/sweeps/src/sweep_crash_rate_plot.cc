// A sweep's crash_rate.png: each group's crash rate (with its Wilson interval) and
// expect-failure rate against the main varied quantity; with two or more grid factors, small
// multiples, one panel per grid cell.

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <string>
#include <utility>
#include <vector>

#include "hpa/scenarios/plot_canvas.h"
#include "harness/sweeps/src/sweep_internal.h"
#include "harness/sweeps/src/sweep_summary_table.h"

namespace hpa::sweep {
namespace {

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

}  // namespace

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

}  // namespace hpa::sweep
