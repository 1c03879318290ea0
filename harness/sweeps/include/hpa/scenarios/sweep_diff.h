#pragma once
// `hpa sweep-diff A B`: a paired comparison of two sweep outputs whose runs pair up (same draws
// and seeds: the same sweep on two builds, or two sweeps that differ in one setting). Per metric:
// the paired difference B - A with an exact 95 % interval (Hodges-Lehmann for continuous
// metrics, conditional binomial for rates), a p-value (Wilcoxon signed-rank, exact McNemar) and
// a verdict by one rule for every metric (docs/sweeps.md).

#include <string>
#include <utility>
#include <vector>

namespace hpa {

/// Two-sided exact McNemar p-value from the discordant pair counts (A only, B only).
double McNemarPValue(int a_only, int b_only);

/// Two-sided Wilcoxon signed-rank p-value of paired differences (zeros dropped; exact for up
/// to 25 non-zero differences, normal approximation with tie correction above).
double SignedRankPValue(const std::vector<double>& differences);

/// The Hodges-Lehmann estimate of a paired shift (the median of the Walsh averages
/// (d_i + d_j) / 2, i <= j) and its 95 % interval: the Walsh averages of rank k + 1 and N - k,
/// k the largest count with P(W+ <= k) <= 0.025 under the signed-rank null (exact up to 50
/// differences, normal approximation above). The interval is the one the signed-rank test
/// inverts: it excludes zero when the test rejects, up to ties, and needs no resampling.
struct ShiftEstimate {
  double estimate = 0.0;
  std::pair<double, double> ci95{0.0, 0.0};
};
ShiftEstimate HodgesLehmann(const std::vector<double>& differences);

/// The paired difference of two rates (B - A) from the discordant counts over n pairs, and its
/// 95 % interval: Clopper-Pearson on the share of the discordant pairs that favour B, scaled by
/// the discordant fraction (exact, conditional on the discordant count).
ShiftEstimate PairedRateDifference(int a_only, int b_only, int n);

/// One metric's comparison. Verdicts (B relative to A), one rule for rates and continuous metrics
/// alike: "better" / "worse" when the test gives p < 0.05, the 95 % interval excludes zero and
/// the estimate is at least the metric's minimum effect (its sign gives the direction); "no
/// difference shown" when the interval lies within plus or minus the minimum effect; else
/// "inconclusive" with the reason (too few pairs, the interval and the test disagree, a
/// difference smaller than the minimum effect, one that cannot be excluded, or slack events
/// missed at different rates for a latency); "not compared" for timing metrics unless asked.
struct MetricDiff {
  std::string name;
  bool higher_is_better = false;
  bool binary = false;      // a rate (0/1 per run), compared with McNemar
  bool timing = false;      // measures the machine, not the controller
  double min_effect = 0.0;  // smallest difference that matters, in `unit`
  std::string unit;
  int pairs = 0;                         // pairs in which both runs have the metric
  int dropped_run_error = 0;             // pairs left out: a run ended in a run error (all)
  int dropped_crashed = 0;               // pairs left out: a run crashed (continuous metrics)
  int dropped_one_side = 0;              // pairs left out: defined in one run only
  int dropped_both = 0;                  // pairs left out: defined in neither run
  double a = 0.0, b = 0.0;               // means over those pairs
  double difference = 0.0;               // mean of b - a
  double estimate = 0.0;                 // the tested shift: Hodges-Lehmann, or the rate's
  std::pair<double, double> ci95{0, 0};  // of the estimate
  double p_value = 1.0;
  std::string verdict = "inconclusive";  // better | worse | no difference shown | inconclusive
                                         // | not compared
  std::string reason;                    // why the verdict is not better / worse
};

/// What `hpa sweep-diff` compares.
struct SweepDiffOptions {
  std::string a_dir, b_dir, out_dir;
  std::string a_where, b_where;     // optional KEY=VALUE filters on the runs' varied values
  bool verdict_timing = false;      // give timing metrics a verdict too (same machine, quiet)
  std::string plot_format = "png";  // diff.png | diff.svg | diff.pdf (and diff.csv)
};

/// The comparison of two loaded sweep outputs.
struct SweepDiff {
  int runs_paired = 0;
  // what differs between A and B ("controller.type: x vs y"), a different estimation basis (truth
  // or estimate, camera, a team's vehicle state) of the pairs whose runs flew among it
  std::vector<std::string> differs;
  std::string build_a, build_b;  // the builds that flew A's and B's runs (DescribeBuild)
  bool same_build = false;       // one build, recorded, flew every run of both
  std::vector<MetricDiff> metrics;
};

/// Pairs the runs of A and B and compares them; throws InputError if they do not pair.
SweepDiff CompareSweeps(const SweepDiffOptions& options);

/// `hpa sweep-diff` entry point (argv[1] is "sweep-diff"); writes diff.json, diff.md, diff.png.
int SweepDiffMain(int argc, char** argv);

}  // namespace hpa
