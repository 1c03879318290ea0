#include "hpa/scenarios/sweep_diff.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "hpa/models/input_error.h"
#include "hpa/scenarios/metric_defs.h"
#include "hpa/scenarios/metrics.h"
#include "hpa/scenarios/provenance.h"
#include "harness/cli/src/cli_parse.h"
#include "harness/cli/src/significant_digits.h"
#include "harness/sweeps/src/sweep_internal.h"
#include "harness/sweeps/src/sweep_diff_basis.h"
#include "harness/sweeps/src/sweep_diff_runs.h"

namespace hpa {
namespace {

using Json = nlohmann::json;
using sweep_diff_runs::ReadRuns;
using sweep_diff_runs::Run;

// A metric read from one run; nullopt where the run does not define it.
struct PairedMetric {
  std::string name;
  bool higher_is_better;
  bool binary;  // a rate: 0/1 per run, compared with McNemar
  std::function<std::optional<double>(const Run&)> read;
  double min_effect;  // smallest difference that matters, in the metric's unit
  std::string unit;
  bool timing = false;  // measures the machine: no verdict between builds unless asked
  // taken over detected slack events only: no verdict when the sides miss events differently
  bool needs_equal_misses = false;
};

// A run that ended in a run error (a stack that never flew, a time limit, a dead worker): no
// metric of it counts, and its pair is left out as a run error, never as a crash.
bool RunError(const Run& r) { return !r.ok || r.metrics.is_null(); }

// A run that crashed (one that ended in a run error did not).
bool Crashed(const Run& r) { return !RunError(r) && r.metrics.value("crashed", false); }

// Continuous metrics are read only from runs that finished without a run error or a crash.
std::function<std::optional<double>(const Run&)> Field(
    std::function<std::optional<double>(const Json&)> read) {
  return [read](const Run& r) -> std::optional<double> {
    if (RunError(r) || Crashed(r)) return std::nullopt;
    return read(r.metrics);
  };
}

// A run that had slack events and missed one (never estimated slack during it).
std::optional<double> MissedSlackEvent(const Run& r) {
  if (RunError(r)) return std::nullopt;
  // find, not operator[]: a const document's operator[] on a missing key is undefined
  const auto latency = r.metrics.find("slack_detection_latency_s");
  if (latency == r.metrics.end() || !latency->is_object()) return std::nullopt;
  return latency->value("missed", 0) > 0 ? 1.0 : 0.0;
}

// Every compared metric: the three per-run rates, then the metrics the metric table marks as
// compared (each with its smallest effect that matters).
const std::vector<PairedMetric>& PairedMetrics() {
  static const std::vector<PairedMetric> defs = [] {
    std::vector<PairedMetric> d = {
        // rates count the runs that ended without a run error: a pair with one is left out
        {"crash_rate", false, true,
         [](const Run& r) -> std::optional<double> {
           if (RunError(r)) return std::nullopt;
           return r.metrics.value("crashed", false) ? 1.0 : 0.0;
         },
         0.05, "fraction"},
        {"expect_failure_rate", false, true,
         [](const Run& r) -> std::optional<double> {
           if (RunError(r)) return std::nullopt;
           const auto expect = r.metrics.find("expect");  // none recorded: passed
           const bool passed = expect == r.metrics.end() || !expect->is_object() ||
                               expect->value("passed", true);
           return passed ? 0.0 : 1.0;
         },
         0.05, "fraction"},
        {"slack_event_missed_rate", false, true, &MissedSlackEvent, 0.05, "fraction"},
    };
    for (const MetricDef& def : MetricDefs()) {
      if (!def.compared) continue;
      d.push_back({def.name, def.better == Better::kHigher, false,
                   Field([&def](const Json& m) { return ReadMetric(def, m); }), def.min_effect,
                   def.unit, def.timing, def.name.rfind("slack_detection_latency", 0) == 0});
    }
    return d;
  }();
  return defs;
}

// Smallest two-sided p-value an exact sign-flip test can reach with n informative pairs.
double SmallestAttainableP(int n) { return n <= 0 ? 1.0 : std::min(1.0, 2.0 / std::pow(2.0, n)); }

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

// A run of A with its partner in B.
using RunPair = std::pair<const Run*, const Run*>;

// Pairs each run of A with the run of B of the same draw, seed and varied values apart from
// the compared setting; InputError when the sweeps do not pair one to one.
std::vector<RunPair> PairRuns(const std::vector<Run>& a, const std::vector<Run>& b,
                              const std::set<std::string>& differing,
                              const SweepDiffOptions& options) {
  std::map<std::string, const Run*> b_by_key;
  for (const Run& r : b) {
    if (!b_by_key.emplace(PairKey(r, differing), &r).second) {
      throw InputError(options.b_dir + "/runs.jsonl", "",
                       "two runs with the same draw, seed and values: a repeated or mixed "
                       "sweep (merge refuses those; use --a-where/--b-where to pick a grid cell)");
    }
  }
  std::vector<RunPair> pairs;
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
  return pairs;
}

// What differs between A and B, for the reader: each differing key with its values on either
// side, and the sweep file when it is not the same.
std::vector<std::string> DescribeDifferences(const std::vector<RunPair>& pairs,
                                             const std::set<std::string>& differing,
                                             const std::vector<Run>& a, const std::vector<Run>& b) {
  std::vector<std::string> differs;
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
    differs.push_back(line + "(B)");
  }
  if (!a.empty() && !b.empty() && a.front().sweep != b.front().sweep) {
    differs.push_back("sweep file: " + a.front().sweep + " (A) vs " + b.front().sweep + " (B)");
  }
  // what flew, when no varied key says it (a flight stack names itself in its hello)
  if (!differing.count("controller.type")) {
    std::set<std::string> ca, cb;
    for (const auto& [ra, rb] : pairs) {
      ca.insert(ra->controller);
      cb.insert(rb->controller);
    }
    if (ca != cb) {
      std::string line = "controller (what flew): ";
      for (const std::string& c : ca) line += c + " ";
      line += "(A) vs ";
      for (const std::string& c : cb) line += c + " ";
      differs.push_back(line + "(B)");
    }
  }
  return differs;
}

// The distinct values of one field over the runs, joined for the reader.
std::set<std::string> Distinct(const std::vector<Run>& runs, std::string Run::*field) {
  std::set<std::string> out;
  for (const Run& r : runs) out.insert(r.*field);
  return out;
}

std::string Join(const std::set<std::string>& values) {
  std::string out;
  for (const std::string& v : values) out += (out.empty() ? "" : ", ") + v;
  return out;
}

// When A and B were flown from different inputs (the sweep_id: the sweep and base files, the
// data files and the flight stack): says so and lists what changed, from each folder's
// inputs.json.
std::vector<std::string> DescribeInputs(const SweepDiffOptions& options, const std::vector<Run>& a,
                                        const std::vector<Run>& b) {
  const std::set<std::string> ids_a = Distinct(a, &Run::inputs_id);
  const std::set<std::string> ids_b = Distinct(b, &Run::inputs_id);
  if (ids_a == ids_b) return {};
  std::vector<std::string> lines = {"inputs: sweep_id " + Join(ids_a) + " (A) vs " + Join(ids_b) +
                                    " (B): what the runs were flown from differs"};
  const auto snap_a = sweep::ReadInputsSnapshot(options.a_dir);
  const auto snap_b = sweep::ReadInputsSnapshot(options.b_dir);
  if (!snap_a || !snap_b) {
    lines.push_back(std::string("what changed cannot be shown: no inputs.json in ") +
                    (!snap_a ? "A" : "B") + " (recorded by an older hpa)");
    return lines;
  }
  for (std::string& change : sweep::DescribeInputChanges(*snap_a, *snap_b)) {
    lines.push_back(std::move(change));
  }
  return lines;
}

// Gives a metric compared over m->pairs pairs its verdict, and the reason when the verdict is
// neither better nor worse. One rule for every metric (docs/sweeps.md): better / worse when the
// test rejects (p < 0.05), the interval excludes zero and the estimate reaches the minimum
// effect; no difference shown when the interval lies within +- the minimum effect; else
// inconclusive, saying why.
void Judge(const PairedMetric& def, bool verdict_timing, MetricDiff* m) {
  const double attainable_p = SmallestAttainableP(m->pairs);
  const bool test_says = m->p_value < 0.05 && m->estimate != 0.0;
  const bool interval_says = m->ci95.first > 0.0 || m->ci95.second < 0.0;
  const bool large = std::fabs(m->estimate) >= def.min_effect;
  const bool within = m->ci95.first >= -def.min_effect && m->ci95.second <= def.min_effect;
  const std::string effect = Fixed(def.min_effect, 3) + " " + def.unit;
  if (def.timing && !verdict_timing) {
    m->verdict = "not compared";
    m->reason = "timing measures the machine; --verdict-timing to compare";
  } else if (test_says && interval_says && large) {
    m->verdict = (m->estimate > 0) == m->higher_is_better ? "better" : "worse";
  } else if (within) {
    m->verdict = "no difference shown";
    m->reason = "the interval [" + Fixed(m->ci95.first, 3) + ", " + Fixed(m->ci95.second, 3) +
                "] lies within +-" + effect;
  } else if (attainable_p >= 0.05) {
    m->verdict = "inconclusive";
    m->reason = std::to_string(m->pairs) + " pairs: the test cannot reach p < 0.05 (smallest p " +
                Fixed(attainable_p, 3) + ")";
  } else if (test_says != interval_says) {
    m->verdict = "inconclusive";
    m->reason = "the interval and the test disagree";
  } else if (test_says && !large) {
    m->verdict = "inconclusive";
    m->reason = "a difference below the minimum effect " + effect +
                ", and the interval does not exclude one of it";
  } else {
    m->verdict = "inconclusive";
    m->reason = "cannot exclude a difference of " + effect;
  }
}

// Whether a pair's runs missed slack events differently (one missed, the other not).
bool MissesDiffer(const RunPair& pair) {
  const auto a = MissedSlackEvent(*pair.first), b = MissedSlackEvent(*pair.second);
  return a && b && *a != *b;
}

// Compares one metric over the pairs in which both runs define it (the pairs left out are
// counted by why: a run error in either run first, then a crash, then the metric undefined):
// means, difference, interval, p-value and verdict.
MetricDiff CompareMetric(const PairedMetric& def, const std::vector<RunPair>& pairs,
                         bool verdict_timing) {
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
    if (RunError(*ra) || RunError(*rb)) {
      ++m.dropped_run_error;
      continue;
    }
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
    return m;
  }
  m.a = sum_a / m.pairs;
  m.b = sum_b / m.pairs;
  m.difference = m.b - m.a;
  const ShiftEstimate shift =
      def.binary ? PairedRateDifference(a_only, b_only, m.pairs) : HodgesLehmann(d);
  m.estimate = shift.estimate;
  m.ci95 = shift.ci95;
  m.p_value = def.binary ? McNemarPValue(a_only, b_only) : SignedRankPValue(d);
  Judge(def, verdict_timing, &m);
  // a latency is taken over the detected events: where one side misses events the other
  // detects, a lower latency may only mean the hard events were missed
  if (def.needs_equal_misses && m.verdict != "not compared" &&
      std::any_of(pairs.begin(), pairs.end(), MissesDiffer)) {
    m.verdict = "inconclusive";
    m.reason =
        "A and B miss slack events in different runs (slack_event_missed_rate): a latency "
        "over the detected events alone would reward missing them";
  }
  return m;
}

}  // namespace

SweepDiff CompareSweeps(const SweepDiffOptions& options) {
  const std::vector<Run> a = ReadRuns(options.a_dir, options.a_where);
  const std::vector<Run> b = ReadRuns(options.b_dir, options.b_where);
  const std::set<std::string> differing = DifferingKeys(a, b);
  // pair by draw, seed and every varied value except the compared setting
  const std::vector<RunPair> pairs = PairRuns(a, b, differing, options);
  SweepDiff diff;
  diff.runs_paired = static_cast<int>(pairs.size());
  diff.differs = DescribeDifferences(pairs, differing, a, b);
  for (std::string& line : DescribeInputs(options, a, b)) diff.differs.push_back(std::move(line));
  // the estimation basis of each pair whose runs both flew: a difference is named as a warning
  std::vector<std::pair<std::optional<std::string>, std::optional<std::string>>> bases;
  for (const auto& [ra, rb] : pairs) {
    if (!RunError(*ra) && !RunError(*rb)) bases.emplace_back(ra->basis, rb->basis);
  }
  for (std::string& line : DescribeBasisDifferences(bases)) diff.differs.push_back(std::move(line));
  const std::set<std::string> builds_a = Distinct(a, &Run::build);
  const std::set<std::string> builds_b = Distinct(b, &Run::build);
  diff.build_a = Join(builds_a);
  diff.build_b = Join(builds_b);
  diff.same_build = builds_a == builds_b && builds_a.size() == 1 && !builds_a.count("not recorded");
  for (const PairedMetric& def : PairedMetrics()) {
    diff.metrics.push_back(CompareMetric(def, pairs, options.verdict_timing));
  }
  return diff;
}

}  // namespace hpa
