// `hpa sweep-diff`: its command line and what it writes (diff.json, diff.md and the plot of
// each compared metric's difference).

#include <stdlib.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "hpa/models/file_io.h"
#include "hpa/scenarios/metrics.h"
#include "hpa/scenarios/plot_canvas.h"
#include "hpa/scenarios/sweep_diff.h"
#include "harness/cli/src/cli_parse.h"
#include "harness/cli/src/significant_digits.h"
#include "harness/sweeps/src/sweep_internal.h"

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

// The byte count of `path` up to and including its last newline, or nothing when the file is
// empty, ends in a newline, cannot be read or is no regular file (a FIFO would block the open;
// ReadRuns refuses it): then it has no torn last line.
std::optional<uintmax_t> WholeLinesBytes(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return std::nullopt;
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return std::nullopt;
  const std::streamoff size = in.tellg();
  char last = '\n';
  if (size <= 0 || !in.seekg(size - 1).get(last) || last == '\n') return std::nullopt;
  // back from the end in blocks to the last newline (0 when the only line is torn)
  constexpr std::streamoff kBlock = 1 << 16;
  std::string block;
  for (std::streamoff end = size; end > 0;) {
    const std::streamoff begin = std::max<std::streamoff>(0, end - kBlock);
    block.resize(static_cast<size_t>(end - begin));
    if (!in.seekg(begin).read(block.data(), static_cast<std::streamsize>(block.size()))) break;
    const size_t newline = block.rfind('\n');
    if (newline != std::string::npos) return static_cast<uintmax_t>(begin) + newline + 1;
    end = begin;
  }
  return 0;
}

// A sweep folder read as `hpa sweep --resume` repairs it: when its runs.jsonl ends in an
// unterminated line (a sweep killed mid-write), that line is left out with a note (its run has
// no record, as after a resume's cut). The folder itself is not changed: its whole lines are
// copied to a temporary folder (beside a link to its inputs.json), which is read instead and
// removed at the end.
class RepairedSweepDir {
 public:
  RepairedSweepDir(const std::string& dir, const std::string& side) : dir_(dir) {
    const std::string jsonl = dir + "/runs.jsonl";
    const std::optional<uintmax_t> keep = WholeLinesBytes(jsonl);
    if (!keep) return;
    namespace fs = std::filesystem;
    std::string pattern = (fs::temp_directory_path() / "hpa-sweep-diff-XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) {
      throw OutputError(pattern, std::string("a temporary folder: ") + std::strerror(errno));
    }
    staged_ = pattern;
    std::error_code ec;
    fs::copy_file(jsonl, staged_ + "/runs.jsonl", ec);
    if (ec || truncate((staged_ + "/runs.jsonl").c_str(), static_cast<off_t>(*keep)) != 0) {
      throw OutputError(staged_ + "/runs.jsonl", "a copy of " + jsonl + " without its torn line");
    }
    if (fs::exists(dir + "/inputs.json")) {
      fs::create_symlink(fs::absolute(dir + "/inputs.json"), staged_ + "/inputs.json", ec);
    }
    std::fprintf(stderr,
                 "hpa: note: %s (%s) ends in an unterminated line (a sweep killed mid-write): its "
                 "last %ju bytes are left out, as hpa sweep --resume cuts them (that run has no "
                 "record)\n",
                 jsonl.c_str(), side.c_str(), fs::file_size(jsonl, ec) - *keep);
  }
  ~RepairedSweepDir() {
    std::error_code ec;
    if (!staged_.empty()) std::filesystem::remove_all(staged_, ec);
  }
  RepairedSweepDir(const RepairedSweepDir&) = delete;
  RepairedSweepDir& operator=(const RepairedSweepDir&) = delete;

  // The folder to read: the repaired copy, or the sweep's own when it needed no repair.
  const std::string& dir() const { return staged_.empty() ? dir_ : staged_; }
  // `text` with the repaired copy's path named as the sweep's folder, for messages.
  std::string Named(std::string text) const {
    if (staged_.empty()) return text;
    for (size_t at = text.find(staged_); at != std::string::npos;
         at = text.find(staged_, at + dir_.size())) {
      text.replace(at, staged_.size(), dir_);
    }
    return text;
  }

 private:
  std::string dir_;     // the sweep's output folder
  std::string staged_;  // the temporary folder with the repaired copy ("" when none)
};

// Compares the two sweeps, each read as --resume repairs it (a torn last line left out).
SweepDiff CompareRepaired(const SweepDiffOptions& options) {
  const RepairedSweepDir a(options.a_dir, "A"), b(options.b_dir, "B");
  SweepDiffOptions read = options;
  read.a_dir = a.dir();
  read.b_dir = b.dir();
  const auto named = [&](const std::string& text) { return b.Named(a.Named(text)); };
  try {
    SweepDiff diff = CompareSweeps(read);
    for (std::string& line : diff.differs) line = named(line);
    return diff;
  } catch (const InputError& e) {
    throw InputError(named(e.file()), e.key(), named(e.detail()));
  } catch (const nlohmann::json::exception& e) {
    // a metric of the wrong type inside a record (a hand-edited runs.jsonl)
    throw InputError(options.a_dir + "/runs.jsonl or " + options.b_dir + "/runs.jsonl", "metrics",
                     std::string("a metric of the wrong type: ") + e.what());
  }
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
      "seed and drawn values; the setting that differs is named. A runs.jsonl that ends in an "
      "unterminated line (a sweep killed mid-write) is read without it, with a note, as hpa "
      "sweep --resume cuts it; the folder is not changed.",
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
  const SweepDiff diff = CompareRepaired(options);
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
