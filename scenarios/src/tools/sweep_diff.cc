#include "hpa/scenarios/sweep_diff.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <random>
#include <set>
#include <sstream>

#include "hpa/models/input_error.h"
#include "hpa/scenarios/metric_defs.h"
#include "hpa/scenarios/metrics.h"
#include "hpa/scenarios/plot_canvas.h"
#include "scenarios/src/tools/cli_parse.h"
#include "scenarios/src/tools/sweep/sweep_internal.h"

namespace hpa {
namespace {

using Json = nlohmann::json;

// One runs.jsonl record reduced to what the comparison needs.
struct Run {
  int draw = 0;
  unsigned long seed = 0;
  std::map<std::string, std::string> values;  // varied key -> value as JSON text
  bool ok = false;                            // finished without a run error
  Json metrics;                               // null if none
  std::string sweep;
};

// A metric read from one run; nullopt where the run does not define it.
struct PairedMetric {
  std::string name;
  bool higher_is_better;
  bool binary;  // a rate: 0/1 per run, compared with McNemar
  std::function<std::optional<double>(const Run&)> read;
  double min_effect;  // smallest difference that matters, in the metric's unit
  std::string unit;
  bool timing = false;  // measures the machine: no verdict between builds unless asked
};

bool Crashed(const Run& r) {
  return !r.ok || r.metrics.is_null() || r.metrics.value("crashed", false);
}

// Continuous metrics are read only from runs that finished without a crash.
std::function<std::optional<double>(const Run&)> Field(
    std::function<std::optional<double>(const Json&)> read) {
  return [read](const Run& r) -> std::optional<double> {
    if (Crashed(r)) return std::nullopt;
    return read(r.metrics);
  };
}

// A run that had slack events and missed one (never estimated slack during it).
std::optional<double> MissedSlackEvent(const Run& r) {
  if (!r.ok || r.metrics.is_null()) return std::nullopt;
  const Json& latency = r.metrics["slack_detection_latency_s"];
  if (!latency.is_object()) return std::nullopt;
  return latency.value("missed", 0) > 0 ? 1.0 : 0.0;
}

// Every compared metric: the three per-run rates, then the metrics the metric table marks as
// compared (each with its smallest effect that matters).
const std::vector<PairedMetric>& PairedMetrics() {
  static const std::vector<PairedMetric> defs = [] {
    std::vector<PairedMetric> d = {
        {"crash_rate", false, true,
         [](const Run& r) -> std::optional<double> { return Crashed(r) ? 1.0 : 0.0; }, 0.05,
         "fraction"},
        {"expect_failure_rate", false, true,
         [](const Run& r) -> std::optional<double> {
           if (!r.ok || r.metrics.is_null()) return 1.0;
           return r.metrics["expect"].value("passed", true) ? 0.0 : 1.0;
         },
         0.05, "fraction"},
        {"slack_event_missed_rate", false, true, &MissedSlackEvent, 0.05, "fraction"},
    };
    for (const MetricDef& def : MetricDefs()) {
      if (!def.compared) continue;
      d.push_back({def.name, def.better == Better::kHigher, false,
                   Field([&def](const Json& m) { return ReadMetric(def, m); }), def.min_effect,
                   def.unit, def.timing});
    }
    return d;
  }();
  return defs;
}

// Whether two varied values are the same: numerically when both are numbers (1 == 1.0 ==
// 1e0), else as exact text.
bool SameValue(const std::string& a, const std::string& b) {
  const auto number = [](const std::string& text) -> std::optional<double> {
    if (text.empty()) return std::nullopt;
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (end != text.c_str() + text.size() || !std::isfinite(v)) return std::nullopt;
    return v;
  };
  const auto x = number(a), y = number(b);
  if (x && y) return *x == *y;
  return a == b;
}

// Smallest two-sided p-value an exact sign-flip test can reach with n informative pairs.
double SmallestAttainableP(int n) { return n <= 0 ? 1.0 : std::min(1.0, 2.0 / std::pow(2.0, n)); }

// Upper end of the Wilson 95 % interval of a proportion k of n.
double WilsonUpper(int k, int n) {
  if (n <= 0) return 1.0;
  const double z = 1.959963984540054, p = static_cast<double>(k) / n;
  const double centre = p + z * z / (2.0 * n);
  const double half = z * std::sqrt(p * (1.0 - p) / n + z * z / (4.0 * n * n));
  return std::min(1.0, (centre + half) / (1.0 + z * z / n));
}

std::vector<Run> ReadRuns(const std::string& dir, const std::string& where) {
  const std::string path = dir + "/runs.jsonl";
  CheckInputFile(path, "a sweep's runs.jsonl");
  std::ifstream in(path);
  if (!in) throw InputError(path, "", "cannot read (not a sweep output folder?)");
  std::string filter_key, filter_value;
  if (!where.empty()) {
    const size_t eq = where.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw InputError("--a-where/--b-where", "", "expected KEY=VALUE, got '" + where + "'");
    }
    filter_key = where.substr(0, eq);
    filter_value = where.substr(eq + 1);
  }
  std::vector<Run> runs;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.empty()) continue;
    Json j;
    try {
      j = Json::parse(line);
    } catch (const Json::exception& e) {
      throw InputError(path, "line " + std::to_string(number), e.what());
    }
    Run r;
    r.draw = j.value("draw", 0);
    r.seed = j.value("seed", 0ul);
    r.sweep = j.value("sweep", "");
    for (const auto& [key, value] : j["values"].items()) {
      r.values[key] = value.is_string() ? value.get<std::string>() : value.dump();
    }
    r.ok = j.value("status", "") == "ok";
    r.metrics = j.contains("metrics") ? j["metrics"] : Json();
    runs.push_back(std::move(r));
  }
  if (runs.empty()) throw InputError(path, "", "no runs recorded");
  if (filter_key.empty()) return runs;
  // the filter: numeric values match numerically; the error lists what there is
  std::vector<Run> kept;
  std::set<std::string> present;
  for (Run& r : runs) {
    const auto it = r.values.find(filter_key);
    if (it == r.values.end()) continue;
    present.insert(it->second);
    if (SameValue(it->second, filter_value)) kept.push_back(std::move(r));
  }
  if (kept.empty()) {
    std::string listed;
    if (present.empty()) {
      std::set<std::string> keys;
      for (const Run& r : runs) {
        for (const auto& [k, v] : r.values) keys.insert(k);
      }
      for (const std::string& k : keys) listed += (listed.empty() ? "" : ", ") + k;
      throw InputError(path, where,
                       "'" + filter_key + "' is not a varied key of this sweep; varied keys: " +
                           (listed.empty() ? "none" : listed));
    }
    for (const std::string& v : present) listed += (listed.empty() ? "" : ", ") + v;
    throw InputError(
        path, where,
        "no run has " + filter_key + " = " + filter_value + "; values present: " + listed);
  }
  return kept;
}

// Keys whose set of values differs between A and B: the setting being compared.
std::set<std::string> DifferingKeys(const std::vector<Run>& a, const std::vector<Run>& b) {
  std::map<std::string, std::set<std::string>> va, vb;
  for (const Run& r : a) {
    for (const auto& [k, v] : r.values) va[k].insert(v);
  }
  for (const Run& r : b) {
    for (const auto& [k, v] : r.values) vb[k].insert(v);
  }
  std::set<std::string> keys;
  for (const auto& [k, v] : va) {
    if (!vb.count(k) || vb[k] != v) keys.insert(k);
  }
  for (const auto& [k, v] : vb) {
    if (!va.count(k)) keys.insert(k);
  }
  return keys;
}

std::string PairKey(const Run& r, const std::set<std::string>& ignore) {
  std::ostringstream key;
  key << r.draw << "/" << r.seed;
  for (const auto& [k, v] : r.values) {
    if (!ignore.count(k)) key << "|" << k << "=" << v;
  }
  return key.str();
}

std::string Fixed(double v, int digits = 4) {
  std::ostringstream out;
  out.precision(digits);
  out << v;
  return out.str();
}

Json NumberOrNull(double v) { return std::isfinite(v) ? Json(v) : Json(); }

void WriteOutputs(const SweepDiff& diff, const SweepDiffOptions& options) {
  MakeOutputDir(options.out_dir);
  Json j;
  j["a"] = options.a_dir;
  j["b"] = options.b_dir;
  j["runs_paired"] = diff.runs_paired;
  j["differs"] = diff.differs;
  j["metrics"] = Json::object();
  for (const MetricDiff& m : diff.metrics) {
    j["metrics"][m.name] = {{"pairs", m.pairs},
                            {"a", NumberOrNull(m.a)},
                            {"b", NumberOrNull(m.b)},
                            {"difference", NumberOrNull(m.difference)},
                            {"ci95", {NumberOrNull(m.ci95.first), NumberOrNull(m.ci95.second)}},
                            {"p_value", NumberOrNull(m.p_value)},
                            {"higher_is_better", m.higher_is_better},
                            {"min_effect", m.min_effect},
                            {"unit", m.unit},
                            {"timing", m.timing},
                            {"pairs_dropped",
                             {{"crashed", m.dropped_crashed},
                              {"defined_in_one_run", m.dropped_one_side},
                              {"defined_in_neither", m.dropped_both}}},
                            {"verdict", m.verdict},
                            {"reason", m.reason}};
  }
  sweep::WriteFileChecked(options.out_dir + "/diff.json", j.dump(1) + "\n");

  std::ostringstream md;
  md << "# sweep-diff: B = `" << options.b_dir << "` against A = `" << options.a_dir << "`\n\n"
     << diff.runs_paired << " paired runs. What differs: "
     << (diff.differs.empty() ? std::string("nothing in the varied values (same sweep)") : "")
     << "\n";
  for (const std::string& d : diff.differs) md << "- " << d << "\n";
  md << "\nDifference = B - A over the pairs where both runs define the metric (continuous "
        "metrics: runs that did not crash; the pairs left out are counted). 95 % interval: "
        "paired bootstrap of the mean. p: Wilcoxon signed-rank (continuous) or exact McNemar "
        "(rates). Verdict: better / worse when p < 0.05 and the interval excludes zero on the "
        "same side; no difference shown when the data bound |B - A| within the metric's minimum "
        "effect (rates: the Wilson bound of the discordant share); otherwise inconclusive, with "
        "the reason. A missed slack event counts in slack_event_missed_rate.\n\n";
  const auto table = [&](bool timing) {
    md << "| metric | min effect | pairs (left out: crash / one run / none) | A | B | B - A | "
          "95 % CI | p | verdict |\n"
       << "|---|---|---|---|---|---|---|---|---|\n";
    for (const MetricDiff& m : diff.metrics) {
      if (m.timing != timing) continue;
      md << "| " << m.name << (m.higher_is_better ? " (higher is better)" : "") << " | "
         << Fixed(m.min_effect, 3) << " " << m.unit << " | " << m.pairs << " (" << m.dropped_crashed
         << " / " << m.dropped_one_side << " / " << m.dropped_both << ") | " << Fixed(m.a) << " | "
         << Fixed(m.b) << " | " << Fixed(m.difference) << " | [" << Fixed(m.ci95.first) << ", "
         << Fixed(m.ci95.second) << "] | " << Fixed(m.p_value, 3) << " | **" << m.verdict << "**"
         << (m.reason.empty() ? "" : ": " + m.reason) << " |\n";
    }
  };
  table(false);
  md << "\n## Timing (measures the machine; not compared unless --verdict-timing)\n\n";
  table(true);

  sweep::WriteFileChecked(options.out_dir + "/diff.md", md.str());

  // one small panel per compared metric: the difference with its interval against zero
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
    const double lo = std::min({m.ci95.first, m.difference, 0.0});
    const double hi = std::max({m.ci95.second, m.difference, 0.0});
    const double pad = hi > lo ? 0.15 * (hi - lo) : 0.01;
    p.SetRange(-1.0, 1.0, lo - pad, hi + pad);
    p.DrawAxes();
    p.Line({-1.0, 1.0}, {0.0, 0.0}, cv::Scalar(0, 0, 0), true);
    p.ErrorBars({0.0}, {m.difference}, {m.ci95.first}, {m.ci95.second}, colour);
  }
  fig.Write(options.out_dir + "/diff", ParsePlotFormat(options.plot_format));
}

}  // namespace

double McNemarPValue(int a_only, int b_only) {
  const int n = a_only + b_only;
  if (n == 0) return 1.0;
  const int k = std::min(a_only, b_only);
  double tail = 0.0;  // P(X <= k), X ~ Binomial(n, 1/2), summed in logs
  for (int i = 0; i <= k; ++i) {
    tail += std::exp(std::lgamma(n + 1.0) - std::lgamma(i + 1.0) - std::lgamma(n - i + 1.0) -
                     n * std::log(2.0));
  }
  return std::min(1.0, 2.0 * tail);
}

double SignedRankPValue(const std::vector<double>& differences) {
  std::vector<double> d;
  for (double x : differences) {
    if (x != 0.0 && std::isfinite(x)) d.push_back(x);
  }
  const int n = static_cast<int>(d.size());
  if (n == 0) return 1.0;
  // mid-ranks of |d| (ties share their average rank)
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](int i, int j) { return std::fabs(d[i]) < std::fabs(d[j]); });
  std::vector<double> rank(n);
  double tie_term = 0.0;
  for (int i = 0; i < n;) {
    int j = i;
    while (j + 1 < n && std::fabs(d[order[j + 1]]) == std::fabs(d[order[i]])) ++j;
    const double mid = 0.5 * (i + j) + 1.0;
    for (int k = i; k <= j; ++k) rank[order[k]] = mid;
    const double t = j - i + 1;
    tie_term += t * t * t - t;
    i = j + 1;
  }
  double w_plus = 0.0;
  for (int i = 0; i < n; ++i) {
    if (d[i] > 0) w_plus += rank[i];
  }
  const double total = n * (n + 1) / 2.0;
  if (n <= 25) {
    // exact null distribution of W+ over doubled (integer) ranks: every sign equally likely
    const int max_sum = static_cast<int>(std::lround(2 * total));
    std::vector<double> count(max_sum + 1, 0.0);
    count[0] = 1.0;
    for (int i = 0; i < n; ++i) {
      const int r2 = static_cast<int>(std::lround(2 * rank[i]));
      for (int s = max_sum; s >= r2; --s) count[s] += count[s - r2];
    }
    const double all = std::pow(2.0, n);
    const int observed = static_cast<int>(std::lround(2 * w_plus));
    const int mirrored = max_sum - observed;
    const int low = std::min(observed, mirrored), high = std::max(observed, mirrored);
    double tails = 0.0;
    for (int s = 0; s <= max_sum; ++s) {
      if (s <= low || s >= high) tails += count[s];
    }
    return std::min(1.0, tails / all);
  }
  const double mean = total / 2.0;
  const double var = n * (n + 1.0) * (2.0 * n + 1.0) / 24.0 - tie_term / 48.0;
  const double z = (std::fabs(w_plus - mean) - 0.5) / std::sqrt(var);
  return std::min(1.0, std::erfc(std::max(0.0, z) / std::sqrt(2.0)));
}

std::pair<double, double> BootstrapMeanCi(const std::vector<double>& differences, int resamples) {
  const size_t n = differences.size();
  if (n == 0) return {0.0, 0.0};
  std::mt19937_64 rng(20261122);
  std::uniform_int_distribution<size_t> pick(0, n - 1);
  std::vector<double> means(resamples);
  for (int r = 0; r < resamples; ++r) {
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i) sum += differences[pick(rng)];
    means[r] = sum / n;
  }
  std::sort(means.begin(), means.end());
  const auto at = [&](double q) {
    return means[std::min<size_t>(means.size() - 1, static_cast<size_t>(q * (resamples - 1)))];
  };
  return {at(0.025), at(0.975)};
}

SweepDiff CompareSweeps(const SweepDiffOptions& options) {
  const std::vector<Run> a = ReadRuns(options.a_dir, options.a_where);
  const std::vector<Run> b = ReadRuns(options.b_dir, options.b_where);
  const std::set<std::string> differing = DifferingKeys(a, b);

  // pair by draw, seed and every varied value except the compared setting
  std::map<std::string, const Run*> b_by_key;
  for (const Run& r : b) {
    if (!b_by_key.emplace(PairKey(r, differing), &r).second) {
      throw InputError(options.b_dir + "/runs.jsonl", "",
                       "two runs with the same draw, seed and values: a repeated or mixed "
                       "sweep (merge refuses those; use --a-where/--b-where to pick a grid cell)");
    }
  }
  std::vector<std::pair<const Run*, const Run*>> pairs;
  for (const Run& r : a) {
    const auto it = b_by_key.find(PairKey(r, differing));
    if (it == b_by_key.end()) {
      throw InputError(options.a_dir + "/runs.jsonl", "",
                       "run with draw " + std::to_string(r.draw) + ", seed " +
                           std::to_string(r.seed) +
                           " has no partner in B: the sweeps do not pair (same run count, "
                           "seeds and drawn values needed)");
    }
    pairs.emplace_back(&r, it->second);
    b_by_key.erase(it);
  }
  if (!b_by_key.empty()) {
    throw InputError(options.b_dir + "/runs.jsonl", "",
                     std::to_string(b_by_key.size()) + " runs have no partner in A");
  }

  SweepDiff diff;
  diff.runs_paired = static_cast<int>(pairs.size());
  for (const std::string& key : differing) {
    std::set<std::string> va, vb;
    for (const auto& [ra, rb] : pairs) {
      if (ra->values.count(key)) va.insert(ra->values.at(key));
      if (rb->values.count(key)) vb.insert(rb->values.at(key));
    }
    std::string line = key + ": ";
    for (const std::string& v : va) line += v + " ";
    line += "(A) vs ";
    for (const std::string& v : vb) line += v + " ";
    diff.differs.push_back(line + "(B)");
  }
  if (!a.empty() && !b.empty() && a.front().sweep != b.front().sweep) {
    diff.differs.push_back("sweep file: " + a.front().sweep + " (A) vs " + b.front().sweep +
                           " (B)");
  }

  for (const PairedMetric& def : PairedMetrics()) {
    MetricDiff m;
    m.name = def.name;
    m.higher_is_better = def.higher_is_better;
    m.binary = def.binary;
    m.min_effect = def.min_effect;
    m.unit = def.unit;
    m.timing = def.timing;
    std::vector<double> d;
    double sum_a = 0.0, sum_b = 0.0;
    int a_only = 0, b_only = 0;
    for (const auto& [ra, rb] : pairs) {
      const auto x = def.read(*ra), y = def.read(*rb);
      if (!x || !y || !std::isfinite(*x) || !std::isfinite(*y)) {
        // say why the pair does not count: a crash, or the metric undefined on one side only
        // (e.g. one run had a re-taut, the other none) or on both
        if (!def.binary && (Crashed(*ra) || Crashed(*rb))) {
          ++m.dropped_crashed;
        } else if (x.has_value() != y.has_value()) {
          ++m.dropped_one_side;
        } else {
          ++m.dropped_both;
        }
        continue;
      }
      d.push_back(*y - *x);
      sum_a += *x;
      sum_b += *y;
      if (*x > *y) ++a_only;
      if (*y > *x) ++b_only;
    }
    m.pairs = static_cast<int>(d.size());
    if (m.pairs == 0) {
      m.a = m.b = m.difference = std::nan("");
      m.ci95 = {std::nan(""), std::nan("")};
      m.p_value = std::nan("");
      m.verdict = "inconclusive";
      m.reason = "no pair in which both runs define it";
      diff.metrics.push_back(m);
      continue;
    }
    m.a = sum_a / m.pairs;
    m.b = sum_b / m.pairs;
    m.difference = m.b - m.a;
    m.ci95 = BootstrapMeanCi(d);
    m.p_value = def.binary ? McNemarPValue(a_only, b_only) : SignedRankPValue(d);
    // what the data could show: the test's smallest attainable p over all pairs, and the
    // difference's bound (rates: the Wilson bound of the discordant share, which limits |B - A|;
    // continuous: the bootstrap interval)
    const double attainable_p = SmallestAttainableP(m.pairs);
    const double bound = def.binary ? WilsonUpper(a_only + b_only, m.pairs)
                                    : std::max(std::fabs(m.ci95.first), std::fabs(m.ci95.second));
    const bool test_says = m.p_value < 0.05 && m.difference != 0.0;
    const bool interval_says = m.ci95.first > 0.0 || m.ci95.second < 0.0;
    if (def.timing && !options.verdict_timing) {
      m.verdict = "not compared";
      m.reason = "timing measures the machine; --verdict-timing to compare";
    } else if (test_says && (def.binary || interval_says)) {
      m.verdict = (m.difference > 0) == m.higher_is_better ? "better" : "worse";
    } else if (attainable_p >= 0.05) {
      m.verdict = "inconclusive";
      m.reason = std::to_string(m.pairs) + " pairs: the test cannot reach p < 0.05 (smallest p " +
                 Fixed(attainable_p, 3) + ")";
    } else if (test_says != interval_says && !def.binary) {
      m.verdict = "inconclusive";
      m.reason = "the interval and the test disagree";
    } else if (bound <= def.min_effect) {
      m.verdict = "no difference shown";
      m.reason = "|B - A| <= " + Fixed(bound, 3) + " " + def.unit + ", within the minimum effect " +
                 Fixed(def.min_effect, 3) + " " + def.unit;
    } else {
      m.verdict = "inconclusive";
      m.reason = "cannot exclude a difference of " + Fixed(def.min_effect, 3) + " " + def.unit +
                 " (bound " + Fixed(bound, 3) + ")";
    }
    diff.metrics.push_back(m);
  }
  return diff;
}

int SweepDiffMain(int argc, char** argv) {
  SweepDiffOptions options;
  CLI::App app{
      "Paired comparison of two sweep outputs (B against A): per metric the mean difference "
      "B - A, its 95 % bootstrap interval, a p-value (Wilcoxon signed-rank; exact McNemar for "
      "rates) and a verdict: better / worse (p < 0.05 and the interval on the same side of "
      "zero), no difference shown (|B - A| bounded within the metric's minimum effect) or "
      "inconclusive (with the reason: too few pairs, test and interval disagree, or the minimum "
      "effect cannot be excluded). Timing metrics are listed apart and not compared unless "
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
  const SweepDiff diff = CompareSweeps(options);
  WriteOutputs(diff, options);
  std::cout << diff.runs_paired << " paired runs";
  for (const std::string& d : diff.differs) std::cout << "; " << d;
  std::cout << "\n";
  for (const MetricDiff& m : diff.metrics) {
    if (m.pairs == 0) {
      std::printf("  %-30s %-19s (%s)\n", m.name.c_str(), m.verdict.c_str(), m.reason.c_str());
      continue;
    }
    std::printf("  %-30s %-19s B - A = %+.4g  [%+.4g, %+.4g]  p = %.3g  (%d pairs)%s%s\n",
                m.name.c_str(), m.verdict.c_str(), m.difference, m.ci95.first, m.ci95.second,
                m.p_value, m.pairs, m.reason.empty() ? "" : ": ", m.reason.c_str());
  }
  std::cout << "wrote " << options.out_dir << "/diff.md, diff.json, diff."
            << PlotExtension(ParsePlotFormat(options.plot_format)) << ", diff.csv\n";
  return 0;
}

}  // namespace hpa
