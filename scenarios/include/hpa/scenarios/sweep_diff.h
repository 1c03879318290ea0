#pragma once
// `hpa sweep-diff A B`: a paired comparison of two sweep outputs whose runs pair up (same draws
// and seeds: the same sweep on two builds, or two sweeps that differ in one setting). Per metric:
// the paired difference B - A with a 95 % bootstrap interval, a p-value (Wilcoxon signed-rank
// for continuous metrics, exact McNemar for crash and expect-failure rates) and a verdict.

#include <string>
#include <utility>
#include <vector>

namespace hpa {

/// Two-sided exact McNemar p-value from the discordant pair counts (A only, B only).
double McNemarPValue(int a_only, int b_only);

/// Two-sided Wilcoxon signed-rank p-value of paired differences (zeros dropped; exact for up
/// to 25 non-zero differences, normal approximation with tie correction above).
double SignedRankPValue(const std::vector<double>& differences);

/// 95 % percentile-bootstrap interval of the mean of `differences` (deterministic: fixed seed).
std::pair<double, double> BootstrapMeanCi(const std::vector<double>& differences,
                                          int resamples = 4000);

/// One metric's comparison. Verdicts (B relative to A): "better" / "worse" when the test gives
/// p < 0.05 and (continuous metrics) the 95 % interval excludes zero on the same side; "no
/// difference shown" when the data bound |B - A| within the metric's minimum effect; else
/// "inconclusive" (too few pairs for the test to reach p < 0.05, the interval and the test
/// disagree, or a difference of the minimum effect cannot be excluded); "not compared" for
/// timing metrics unless asked.
struct MetricDiff {
  std::string name;
  bool higher_is_better = false;
  bool binary = false;      // a rate (0/1 per run), compared with McNemar
  bool timing = false;      // measures the machine, not the controller
  double min_effect = 0.0;  // smallest difference that matters, in `unit`
  std::string unit;
  int pairs = 0;                         // pairs in which both runs have the metric
  int dropped_crashed = 0;               // pairs left out: a run crashed (continuous metrics)
  int dropped_one_side = 0;              // pairs left out: defined in one run only
  int dropped_both = 0;                  // pairs left out: defined in neither run
  double a = 0.0, b = 0.0;               // means over those pairs
  double difference = 0.0;               // mean of b - a
  std::pair<double, double> ci95{0, 0};  // of the difference
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
  std::vector<std::string> differs;  // what differs between A and B ("controller.type: x vs y")
  std::vector<MetricDiff> metrics;
};

/// Pairs the runs of A and B and compares them; throws InputError if they do not pair.
SweepDiff CompareSweeps(const SweepDiffOptions& options);

/// `hpa sweep-diff` entry point (argv[1] is "sweep-diff"); writes diff.json, diff.md, diff.png.
int SweepDiffMain(int argc, char** argv);

}  // namespace hpa
