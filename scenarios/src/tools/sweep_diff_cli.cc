// `hpa sweep-diff`: its command line and what it writes (diff.json, diff.md and the plot of
// each compared metric's difference).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "hpa/models/file_io.h"
#include "hpa/scenarios/metrics.h"
#include "hpa/scenarios/plot_canvas.h"
#include "hpa/scenarios/sweep_diff.h"
#include "scenarios/src/tools/cli_parse.h"
#include "scenarios/src/tools/significant_digits.h"
#include "scenarios/src/tools/sweep/sweep_internal.h"

namespace hpa {
namespace {

using Json = nlohmann::json;

// A number for diff.json; non-finite values (a metric no pair defines) are null.
Json NumberOrNull(double v) { return std::isfinite(v) ? Json(v) : Json(); }

// The pairs a metric left out for a run error in either run: every pair its counts do not hold.
int RunErrorPairs(const SweepDiff& diff, const MetricDiff& m) {
  return diff.runs_paired - m.pairs - m.dropped_crashed - m.dropped_one_side - m.dropped_both;
}

// Writes diff.json: the runs paired, what differs and every metric's comparison.
void WriteDiffJson(const SweepDiff& diff, const SweepDiffOptions& options) {
  Json j;
  j["a"] = options.a_dir;
  j["b"] = options.b_dir;
  j["runs_paired"] = diff.runs_paired;
  j["differs"] = diff.differs;
  j["build"] = {{"same", diff.same_build}, {"a", diff.build_a}, {"b", diff.build_b}};
  j["metrics"] = Json::object();
  for (const MetricDiff& m : diff.metrics) {
    j["metrics"][m.name] = {{"pairs", m.pairs},
                            {"a", NumberOrNull(m.a)},
                            {"b", NumberOrNull(m.b)},
                            {"difference", NumberOrNull(m.difference)},
                            {"estimate", NumberOrNull(m.estimate)},
                            {"ci95", {NumberOrNull(m.ci95.first), NumberOrNull(m.ci95.second)}},
                            {"p_value", NumberOrNull(m.p_value)},
                            {"higher_is_better", m.higher_is_better},
                            {"min_effect", m.min_effect},
                            {"unit", m.unit},
                            {"timing", m.timing},
                            {"pairs_dropped",
                             {{"run_error", RunErrorPairs(diff, m)},
                              {"crashed", m.dropped_crashed},
                              {"defined_in_one_run", m.dropped_one_side},
                              {"defined_in_neither", m.dropped_both}}},
                            {"verdict", m.verdict},
                            {"reason", m.reason}};
  }
  WriteFileAtomic(options.out_dir + "/diff.json", j.dump(1) + "\n");
}

// One table of diff.md: the timing metrics or all the others, a row per metric.
void DiffTableMarkdown(const SweepDiff& diff, bool timing, std::ostringstream& md) {
  md << "| metric | min effect | pairs (left out: run error / crash / one run / none) | A | B | "
        "B - A, mean | B - A, estimate | 95 % CI | p | verdict |\n"
     << "|---|---|---|---|---|---|---|---|---|---|\n";
  for (const MetricDiff& m : diff.metrics) {
    if (m.timing != timing) continue;
    md << "| " << m.name << (m.higher_is_better ? " (higher is better)" : "") << " | "
       << Fixed(m.min_effect, 3) << " " << m.unit << " | " << m.pairs << " ("
       << RunErrorPairs(diff, m) << " / " << m.dropped_crashed << " / " << m.dropped_one_side
       << " / " << m.dropped_both << ") | " << Fixed(m.a) << " | " << Fixed(m.b) << " | "
       << Fixed(m.difference) << " | " << Fixed(m.estimate) << " | [" << Fixed(m.ci95.first) << ", "
       << Fixed(m.ci95.second) << "] | " << Fixed(m.p_value, 3) << " | **" << m.verdict << "**"
       << (m.reason.empty() ? "" : ": " + m.reason) << " |\n";
  }
}

// Writes diff.md: what differs, how the comparison is made, then the tables (timing apart).
void WriteDiffMarkdown(const SweepDiff& diff, const SweepDiffOptions& options) {
  std::ostringstream md;
  md << "# sweep-diff: B = `" << options.b_dir << "` against A = `" << options.a_dir << "`\n\n"
     << diff.runs_paired << " paired runs. What differs: "
     << (diff.differs.empty() ? std::string("nothing in the varied values (same sweep)") : "")
     << "\n";
  for (const std::string& d : diff.differs) md << "- " << d << "\n";
  if (diff.same_build) {
    md << "\nBuild: the same for A and B (" << diff.build_a << ").\n";
  } else {
    md << "\nBuild: **not the same** (timing and bit-level results may differ): A " << diff.build_a
       << "; B " << diff.build_b << ".\n";
  }
  md << "\nDifference = B - A over the pairs where both runs define the metric (continuous "
        "metrics: runs that did not crash; rates: runs that ended without a run error; the pairs "
        "left out are counted). Estimate and 95 % interval: Hodges-Lehmann (continuous, the "
        "interval the signed-rank test inverts) or the discordant pairs' difference with its "
        "exact binomial interval (rates). p: Wilcoxon signed-rank or exact McNemar. Verdict, one "
        "rule for every metric: better / worse when p < 0.05, the interval excludes zero and the "
        "estimate reaches the minimum effect; no difference shown when the interval lies within "
        "+- the minimum effect; otherwise inconclusive, with the reason. A missed slack event "
        "counts in slack_event_missed_rate, and a slack detection latency gets no verdict when A "
        "and B miss events in different runs.\n\n";
  DiffTableMarkdown(diff, false, md);
  md << "\n## Timing (measures the machine; not compared unless --verdict-timing)\n\n";
  DiffTableMarkdown(diff, true, md);
  WriteFileAtomic(options.out_dir + "/diff.md", md.str());
}

// Writes the diff plot: one small panel per compared metric, its difference with its interval
// against zero, coloured by the verdict.
void WriteDiffPlot(const SweepDiff& diff, const SweepDiffOptions& options) {
  std::vector<const MetricDiff*> compared;
  for (const MetricDiff& m : diff.metrics) {
    if (m.pairs > 0 && m.verdict != "not compared") compared.push_back(&m);
  }
  const int cols = 3, w = 420, h = 260;
  const int rows = std::max(1, (static_cast<int>(compared.size()) + cols - 1) / cols);
  Figure fig(cols * w, rows * h);
  for (size_t i = 0; i < compared.size(); ++i) {
    const MetricDiff& m = *compared[i];
    const cv::Scalar colour = m.verdict == "better"  ? cv::Scalar(60, 160, 40)
                              : m.verdict == "worse" ? cv::Scalar(40, 40, 210)
                                                     : cv::Scalar(120, 120, 120);
    PlotPanel p(&fig,
                cv::Rect(static_cast<int>(i % cols) * w, static_cast<int>(i / cols) * h, w, h),
                m.name, "B - A: " + m.verdict + " (p = " + Fixed(m.p_value, 2) + ")",
                "B - A [" + (m.unit.empty() || m.unit == "-" ? std::string("1") : m.unit) + "]");
    const double lo = std::min({m.ci95.first, m.estimate, 0.0});
    const double hi = std::max({m.ci95.second, m.estimate, 0.0});
    const double pad = hi > lo ? 0.15 * (hi - lo) : 0.01;
    p.SetRange(-1.0, 1.0, lo - pad, hi + pad);
    p.DrawAxes();
    p.Line({-1.0, 1.0}, {0.0, 0.0}, cv::Scalar(0, 0, 0), true);
    p.ErrorBars({0.0}, {m.estimate}, {m.ci95.first}, {m.ci95.second}, colour);
  }
  fig.Write(options.out_dir + "/diff", ParsePlotFormat(options.plot_format));
}

// Writes everything `hpa sweep-diff` outputs into its --out folder.
void WriteOutputs(const SweepDiff& diff, const SweepDiffOptions& options) {
  MakeOutputDir(options.out_dir);
  WriteDiffJson(diff, options);
  WriteDiffMarkdown(diff, options);
  WriteDiffPlot(diff, options);
}

}  // namespace

int SweepDiffMain(int argc, char** argv) {
  SweepDiffOptions options;
  CLI::App app{
      "Paired comparison of two sweep outputs (B against A): per metric the paired difference "
      "B - A (mean, and the tested estimate with its exact 95 % interval: Hodges-Lehmann, or "
      "exact binomial for rates), a p-value (Wilcoxon signed-rank; exact McNemar for rates) and "
      "a verdict by one rule: better / worse (p < 0.05, the interval excludes zero and the "
      "estimate reaches the metric's minimum effect), no difference shown (the interval within "
      "+- the minimum effect) or inconclusive (with the reason: too few pairs, test and "
      "interval disagree, below the minimum effect, the minimum effect not excluded, or slack "
      "events missed differently). Timing metrics are listed apart and not compared unless "
      "--verdict-timing. Writes DIR/diff.json, DIR/diff.md and DIR/diff.png. Runs pair by draw, "
      "seed and drawn values; the setting that differs is named.",
      "hpa sweep-diff"};
  app.add_option("A", options.a_dir, "sweep output folder (runs.jsonl), the reference")->required();
  app.add_option("B", options.b_dir, "sweep output folder compared against A")->required();
  app.add_option("--out", options.out_dir, "output folder")->required();
  app.add_option("--a-where", options.a_where,
                 "KEY=VALUE: only A's runs with this varied value (e.g. controller.type=hpa_mpc; "
                 "numbers match numerically)");
  app.add_option("--b-where", options.b_where,
                 "KEY=VALUE: only B's runs with this value (numbers match numerically: 1 = 1.0)");
  app.add_flag("--verdict-timing", options.verdict_timing,
               "also give timing metrics (solve time) a verdict: only for runs on one quiet "
               "machine");
  app.add_option("--plot-format", options.plot_format,
                 "png | svg | pdf: the format of diff.png (diff.csv holds its numbers)");
  if (const auto code = ParseCommandLine(app, argc, argv)) return *code;
  ParsePlotFormat(options.plot_format);  // refused before any work
  SweepDiff diff;
  try {
    diff = CompareSweeps(options);
  } catch (const nlohmann::json::exception& e) {
    // a metric of the wrong type inside a record (a hand-edited runs.jsonl)
    throw InputError(options.a_dir + "/runs.jsonl or " + options.b_dir + "/runs.jsonl", "metrics",
                     std::string("a metric of the wrong type: ") + e.what());
  }
  WriteOutputs(diff, options);
  std::cout << diff.runs_paired << " paired runs";
  for (const std::string& d : diff.differs) std::cout << "; " << d;
  std::cout << "\n"
            << (diff.same_build ? "same build: " + diff.build_a
                                : "builds differ: A " + diff.build_a + "; B " + diff.build_b)
            << "\n";
  for (const MetricDiff& m : diff.metrics) {
    if (m.pairs == 0) {
      std::printf("  %-30s %-19s (%s)\n", m.name.c_str(), m.verdict.c_str(), m.reason.c_str());
      continue;
    }
    std::printf("  %-30s %-19s B - A = %+.4g  [%+.4g, %+.4g]  p = %.3g  (%d pairs)%s%s\n",
                m.name.c_str(), m.verdict.c_str(), m.estimate, m.ci95.first, m.ci95.second,
                m.p_value, m.pairs, m.reason.empty() ? "" : ": ", m.reason.c_str());
  }
  std::cout << "wrote " << options.out_dir << "/diff.md, diff.json, diff."
            << PlotExtension(ParsePlotFormat(options.plot_format)) << ", diff.csv\n";
  return 0;
}

}  // namespace hpa
