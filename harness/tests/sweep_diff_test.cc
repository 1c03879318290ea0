// sweep-diff statistics against textbook values (R: mcnemar exact = binom.test on the
// discordant pairs; wilcox.test(x, exact = TRUE)).

#include "hpa/scenarios/sweep_diff.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "hpa/models/input_error.h"
#include "models/tests/temp_dir.h"

namespace hpa {
namespace {

TEST(SweepDiffTest, McNemarExactMatchesTheBinomialTest) {
  EXPECT_DOUBLE_EQ(McNemarPValue(0, 0), 1.0);
  EXPECT_NEAR(McNemarPValue(0, 10), 2.0 / 1024.0, 1e-12);         // binom.test(0, 10)
  EXPECT_NEAR(McNemarPValue(3, 7), 2.0 * 176.0 / 1024.0, 1e-12);  // binom.test(3, 10)
  EXPECT_DOUBLE_EQ(McNemarPValue(5, 5), 1.0);
}

TEST(SweepDiffTest, SignedRankExactMatchesR) {
  EXPECT_NEAR(SignedRankPValue({1, 2, 3, 4, 5, 6, 7, 8, 9, 10}), 2.0 / 1024.0, 1e-12);
  EXPECT_NEAR(SignedRankPValue({1, -2, 3, -4, 5}), 0.8125, 1e-12);  // V = 9
  EXPECT_DOUBLE_EQ(SignedRankPValue({0, 0, 0}), 1.0);               // all ties at zero
}

TEST(SweepDiffTest, SignedRankNormalApproximationForLargeSamples) {
  std::vector<double> shifted, symmetric;
  for (int i = 1; i <= 40; ++i) {
    shifted.push_back(i % 5 == 0 ? -0.1 * i : 0.1 * i);  // mostly positive
    symmetric.push_back(i % 2 ? 0.1 * i : -0.1 * i);
  }
  // W+ = 820 - 180 = 640, mean 410, var 40 * 41 * 81 / 24: z = (230 - 0.5) / sqrt(5535)
  EXPECT_NEAR(SignedRankPValue(shifted), std::erfc((229.5 / std::sqrt(5535.0)) / std::sqrt(2.0)),
              1e-12);
  EXPECT_GT(SignedRankPValue(symmetric), 0.5);
}

TEST(SweepDiffTest, HodgesLehmannMatchesR) {
  // R: wilcox.test(1:10, conf.int = TRUE): estimate 5.5, 95 % interval [3, 8]
  std::vector<double> d;
  for (int i = 1; i <= 10; ++i) d.push_back(i);
  const ShiftEstimate s = HodgesLehmann(d);
  EXPECT_DOUBLE_EQ(s.estimate, 5.5);
  EXPECT_DOUBLE_EQ(s.ci95.first, 3.0);
  EXPECT_DOUBLE_EQ(s.ci95.second, 8.0);
  // deterministic: no resampling, the same answer every time
  EXPECT_EQ(HodgesLehmann(d).ci95, s.ci95);
}

TEST(SweepDiffTest, PairedRateDifferenceIsExact) {
  // 8 discordant pairs, all favouring B, over 30 pairs: +8/30; Clopper-Pearson on 8 of 8 is
  // [0.025^(1/8), 1] = [0.631, 1], scaled by 8/30
  const ShiftEstimate s = PairedRateDifference(0, 8, 30);
  EXPECT_NEAR(s.estimate, 8.0 / 30.0, 1e-12);
  EXPECT_NEAR(s.ci95.first, 8.0 / 30.0 * (2.0 * std::pow(0.025, 1.0 / 8.0) - 1.0), 1e-6);
  EXPECT_NEAR(s.ci95.second, 8.0 / 30.0, 1e-9);
  // no discordant pair in 6: |B - A| is bounded only by 1 - 0.025^(1/6) = 0.459
  const ShiftEstimate none = PairedRateDifference(0, 0, 6);
  EXPECT_NEAR(none.ci95.second, 1.0 - std::pow(0.025, 1.0 / 6.0), 1e-12);
}

// --- the verdicts of CompareSweeps on written runs.jsonl files ------------------------------

// One run's record as `hpa sweep` writes it, with the metrics sweep-diff reads.
struct FakeRun {
  int draw = 0;
  double weight = 1.0;       // the varied value (controller.perception_weight)
  double deviation_m = 0.1;  // quad_position_deviation_max_m
  double in_view = 1.0;      // payload_in_fov_fraction
  double solve_ms = 0.2;     // mpc_solve_ms.median
  bool crashed = false;
  bool error = false;    // a run error (time limit): status "error", no metrics
  int slack_missed = 0;  // slack_detection_latency_s.missed
  int retauts = 1;       // retaut.count
};

// Writes `runs` as DIR/runs.jsonl (DIR under the test's temporary folder) and returns DIR.
std::string WriteSweep(const std::string& name, const std::vector<FakeRun>& runs) {
  const std::string dir = TestTempDir() + name;
  mkdir(dir.c_str(), 0755);
  std::ofstream out(dir + "/runs.jsonl");
  for (const FakeRun& r : runs) {
    nlohmann::json m = {
        {"crashed", r.crashed},
        {"payload_rmse_m", {0.01, 0.01, 0.01}},
        {"quad_position_deviation_max_m", r.deviation_m},
        {"payload_in_fov_fraction", r.in_view},
        {"mode_accuracy", 0.99},
        {"retaut",
         {{"count", r.retauts}, {"quad_vz_min_mps", -0.3}, {"peak_body_rate_radps", 1.0}}},
        {"slack_detection_latency_s",
         {{"mean", 0.02},
          {"max", r.slack_missed > 0 ? nlohmann::json() : nlohmann::json(0.03)},
          {"missed", r.slack_missed}}},
        {"mpc_solve_ms", {{"median", r.solve_ms}}},
        {"expect", {{"passed", true}}}};
    nlohmann::json j = {{"sweep", "fake.yaml"},
                        {"run", r.draw},
                        {"draw", r.draw},
                        {"seed", 1000 + r.draw},
                        {"values", {{"controller.perception_weight", r.weight}}},
                        {"status", r.error ? "error" : "ok"},
                        {"metrics", r.error ? nlohmann::json() : m}};
    out << j.dump() << "\n";
  }
  return dir;
}

// n runs with deviations, views and solve times drawn from `seed` (machine-noise-like timing).
std::vector<FakeRun> RandomRuns(int n, unsigned seed, double weight = 1.0) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<FakeRun> runs(n);
  for (int i = 0; i < n; ++i) {
    runs[i].draw = i;
    runs[i].weight = weight;
    runs[i].deviation_m = 0.1 + 0.02 * noise(rng);
    runs[i].in_view = std::min(1.0, 0.97 + 0.01 * noise(rng));
    runs[i].solve_ms = 0.2 + 0.05 * noise(rng);
  }
  return runs;
}

const MetricDiff& Find(const SweepDiff& diff, const std::string& name) {
  for (const MetricDiff& m : diff.metrics) {
    if (m.name == name) return m;
  }
  throw std::runtime_error("no metric " + name);
}

// A sweep against itself: nothing better or worse; the timing metric not compared at all; 40
// pairs bound every difference at zero, within each minimum effect, except the rates, whose
// Wilson bound with no discordant pair of 40 is 0.088 (above 0.05): inconclusive.
TEST(SweepDiffVerdictTest, IdenticalSweepsShowNoDifferenceAndDoNotCompareTiming) {
  const std::string dir = WriteSweep("a", RandomRuns(40, 1));
  SweepDiffOptions options;
  options.a_dir = options.b_dir = dir;
  const SweepDiff diff = CompareSweeps(options);
  for (const MetricDiff& m : diff.metrics) {
    EXPECT_NE(m.verdict, "better") << m.name;
    EXPECT_NE(m.verdict, "worse") << m.name;
  }
  EXPECT_EQ(Find(diff, "mpc_solve_median_ms").verdict, "not compared");
  EXPECT_EQ(Find(diff, "quad_position_deviation_max_m").verdict, "no difference shown");
  EXPECT_EQ(Find(diff, "crash_rate").verdict, "inconclusive");
  // 200 pairs bound a rate difference below 0.05 (Wilson 0.019)
  const std::string big = WriteSweep("big", RandomRuns(200, 2));
  options.a_dir = options.b_dir = big;
  EXPECT_EQ(Find(CompareSweeps(options), "crash_rate").verdict, "no difference shown");
}

// Two sweeps on a noisy machine: their solve times differ by noise alone; that is never a
// verdict between builds unless asked.
TEST(SweepDiffVerdictTest, TimingIsReportedApart) {
  std::vector<FakeRun> b = RandomRuns(40, 1);
  for (FakeRun& r : b) r.solve_ms *= 1.3;  // a busier machine
  SweepDiffOptions options;
  options.a_dir = WriteSweep("a", RandomRuns(40, 1));
  options.b_dir = WriteSweep("b", b);
  EXPECT_EQ(Find(CompareSweeps(options), "mpc_solve_median_ms").verdict, "not compared");
  options.verdict_timing = true;
  EXPECT_EQ(Find(CompareSweeps(options), "mpc_solve_median_ms").verdict, "worse");
}

// Four pairs cannot show anything (the exact signed-rank p is at least 2 / 2^4 = 0.125), even
// when B is worse in every pair.
TEST(SweepDiffVerdictTest, FourPairsAreInconclusive) {
  std::vector<FakeRun> a = RandomRuns(4, 3), b = a;
  for (FakeRun& r : b) r.deviation_m += 0.1;
  SweepDiffOptions options;
  options.a_dir = WriteSweep("a", a);
  options.b_dir = WriteSweep("b", b);
  const SweepDiff four = CompareSweeps(options);
  const MetricDiff& m = Find(four, "quad_position_deviation_max_m");
  EXPECT_EQ(m.verdict, "inconclusive");
  EXPECT_NE(m.reason.find("cannot reach p < 0.05"), std::string::npos) << m.reason;
  // six pairs can: 2 / 2^6 = 0.031
  a = RandomRuns(6, 3);
  b = a;
  for (FakeRun& r : b) r.deviation_m += 0.1;
  options.a_dir = WriteSweep("a6", a);
  options.b_dir = WriteSweep("b6", b);
  EXPECT_EQ(Find(CompareSweeps(options), "quad_position_deviation_max_m").verdict, "worse");
}

// The verdict never contradicts the interval: over many random comparisons, "no difference
// shown" only with an interval that holds zero and lies within the minimum effect, "better" /
// "worse" (continuous) only with an interval on the verdict's side of zero.
TEST(SweepDiffVerdictTest, VerdictAgreesWithTheInterval) {
  int verdicts_checked = 0;
  for (unsigned seed = 0; seed < 30; ++seed) {
    std::vector<FakeRun> a = RandomRuns(12, 100 + seed), b = RandomRuns(12, 200 + seed);
    for (size_t i = 0; i < a.size(); ++i) b[i].deviation_m = a[i].deviation_m + 0.004 * (seed % 5);
    SweepDiffOptions options;
    options.a_dir = WriteSweep("a" + std::to_string(seed), a);
    options.b_dir = WriteSweep("b" + std::to_string(seed), b);
    for (const MetricDiff& m : CompareSweeps(options).metrics) {
      if (m.binary || m.pairs == 0) continue;
      ++verdicts_checked;
      // the one rule (docs/sweeps.md): equivalence is the interval within +- the minimum
      // effect; a verdict needs the interval off zero and the estimate at the minimum effect
      if (m.verdict == "no difference shown") {
        EXPECT_LE(std::max(-m.ci95.first, m.ci95.second), m.min_effect) << m.name;
      } else if (m.verdict == "better" || m.verdict == "worse") {
        EXPECT_TRUE(m.ci95.first > 0.0 || m.ci95.second < 0.0) << m.name;
        EXPECT_GE(std::fabs(m.estimate), m.min_effect) << m.name;
      }
    }
  }
  EXPECT_GT(verdicts_checked, 100);
}

// A run that misses a slack event is a failure of that run, not a pair left out: B misses
// events in 8 of 30 runs where A missed none.
TEST(SweepDiffVerdictTest, MissedSlackEventsCountAsFailures) {
  std::vector<FakeRun> a = RandomRuns(30, 4), b = a;
  for (int i = 0; i < 8; ++i) b[i].slack_missed = 1;
  for (int i = 0; i < 3; ++i) b[20 + i].retauts = 0;  // no re-taut in three B runs
  SweepDiffOptions options;
  options.a_dir = WriteSweep("a", a);
  options.b_dir = WriteSweep("b", b);
  const SweepDiff diff = CompareSweeps(options);
  EXPECT_EQ(Find(diff, "slack_event_missed_rate").verdict, "worse");  // McNemar p = 2 / 2^8
  EXPECT_EQ(Find(diff, "slack_detection_latency_max_s").dropped_one_side, 8);
  // the latency over the events each side detected: withheld, missing must not pay
  EXPECT_EQ(Find(diff, "slack_detection_latency_max_s").verdict, "inconclusive");
  EXPECT_NE(Find(diff, "slack_detection_latency_max_s").reason.find("miss"), std::string::npos);
  EXPECT_EQ(Find(diff, "retaut_quad_vz_min_mps").dropped_one_side, 3);
  EXPECT_EQ(Find(diff, "retaut_quad_vz_min_mps").pairs, 27);
}

// The direction comes from the tested statistic: 34 pairs 1 mm worse and 6 pairs 10 cm better
// have a mean 1.4 cm better but a rank test that says worse; the shift estimate says worse by
// 1 mm (interval [1, 1] mm), within the 1 cm that matters: no difference shown, never "better"
// from the mean.
TEST(SweepDiffVerdictTest, TheDirectionAndTheSizeComeFromTheTestedShift) {
  std::vector<FakeRun> a = RandomRuns(40, 7), b = a;
  for (int i = 0; i < 40; ++i) b[i].deviation_m = a[i].deviation_m + (i < 34 ? 0.001 : -0.1);
  SweepDiffOptions options;
  options.a_dir = WriteSweep("shift_a", a);
  options.b_dir = WriteSweep("shift_b", b);
  const SweepDiff diff = CompareSweeps(options);
  const MetricDiff& m = Find(diff, "quad_position_deviation_max_m");
  EXPECT_LT(m.difference, 0.0);  // the mean
  EXPECT_GT(m.estimate, 0.0);    // the rank test's shift
  EXPECT_LT(m.p_value, 0.05);
  EXPECT_NEAR(m.estimate, 0.001, 1e-9);
  EXPECT_EQ(m.verdict, "no difference shown") << m.reason;
}

// Identical runs: every metric equivalent or, for rates whose six pairs cannot bound a
// difference of 0.05, inconclusive; never better or worse. Run errors are not crashes.
TEST(SweepDiffVerdictTest, IdenticalPairsAndRunErrors) {
  const std::vector<FakeRun> a = RandomRuns(6, 3);
  SweepDiffOptions options;
  options.a_dir = WriteSweep("same_a", a);
  options.b_dir = WriteSweep("same_b", a);
  for (const MetricDiff& m : CompareSweeps(options).metrics) {
    EXPECT_NE(m.verdict, "better") << m.name;
    EXPECT_NE(m.verdict, "worse") << m.name;
    if (!m.binary && !m.timing && m.pairs > 0) {
      EXPECT_EQ(m.verdict, "no difference shown") << m.name;
    }
  }
  // 30 pairs, three of B's runs hit the time limit: left out of the crash rate, not crashes
  std::vector<FakeRun> ok = RandomRuns(30, 5), errors = ok;
  for (int i = 0; i < 3; ++i) errors[i].error = true;
  options.a_dir = WriteSweep("err_a", ok);
  options.b_dir = WriteSweep("err_b", errors);
  const SweepDiff with_errors = CompareSweeps(options);
  const MetricDiff& crash = Find(with_errors, "crash_rate");
  EXPECT_EQ(crash.pairs, 27);
  EXPECT_EQ(crash.difference, 0.0);
  EXPECT_NE(crash.verdict, "worse");
}

// --a-where matches numbers numerically (1 finds the runs written 1.0); a value no run has is
// refused with the values that are there.
TEST(SweepDiffVerdictTest, WhereMatchesNumbersAndListsTheValuesPresent) {
  std::vector<FakeRun> runs = RandomRuns(10, 5, 1.0), low = RandomRuns(10, 5, 0.3);
  runs.insert(runs.end(), low.begin(), low.end());
  const std::string dir = WriteSweep("grid", runs);
  SweepDiffOptions options;
  options.a_dir = options.b_dir = dir;
  options.a_where = "controller.perception_weight=1";
  options.b_where = "controller.perception_weight=3e-1";
  EXPECT_EQ(CompareSweeps(options).runs_paired, 10);
  options.b_where = "controller.perception_weight=2";
  try {
    CompareSweeps(options);
    FAIL() << "a value no run has was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("values present: 0.3, 1.0"), std::string::npos)
        << e.what();
  }
  options.b_where = "controller.gain=2";
  try {
    CompareSweeps(options);
    FAIL() << "a key that is not varied was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("varied keys: controller.perception_weight"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace hpa
