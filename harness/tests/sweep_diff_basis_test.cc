// sweep-diff on written runs.jsonl files: the estimation basis each pair flew on (truth or an
// estimate, the camera, a team's vehicle state) named under "What differs" when it differs, and
// the left-out pairs of every metric, rates included, counted as run errors or crashes by what
// ended each run.

#include "harness/sweeps/src/sweep_diff_basis.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hpa/scenarios/sweep_diff.h"
#include "models/tests/temp_dir.h"

namespace hpa {
namespace {

using Json = nlohmann::json;

// One run's record as `hpa sweep` writes it, with what the basis and the rates read.
struct BasisRun {
  std::string camera = "analytic";  // metrics.json's camera: ground_truth | render | analytic
  std::string vehicle_state;        // a team's team.vehicle_state; empty: a single vehicle
  bool crashed = false;
  bool expect_passed = true;
  bool run_error = false;       // status "error"
  bool metrics_written = true;  // false: a dead worker's record (metrics null)
  double deviation_m = 0.1;     // quad_position_deviation_max_m
};

// Writes runs (draw i for the i-th) as DIR/runs.jsonl under the test's temporary folder.
std::string WriteRuns(const std::string& name, const std::vector<BasisRun>& runs) {
  const std::string dir = TestTempDir() + name;
  mkdir(dir.c_str(), 0755);
  std::ofstream out(dir + "/runs.jsonl");
  for (size_t i = 0; i < runs.size(); ++i) {
    const BasisRun& r = runs[i];
    Json m = {{"camera", r.camera},
              {"crashed", r.crashed},
              {"run_error", r.run_error ? Json("flight stack 'x' exited") : Json()},
              {"quad_position_deviation_max_m", r.deviation_m},
              {"expect", {{"passed", r.expect_passed}}}};
    if (!r.vehicle_state.empty()) m["team"] = {{"vehicle_state", r.vehicle_state}};
    const Json j = {{"sweep", "s.yaml"},
                    {"draw", i},
                    {"seed", 100 + i},
                    {"values", Json::object()},
                    {"status", r.run_error ? "error" : "ok"},
                    {"metrics", r.metrics_written ? m : Json()}};
    out << j.dump() << "\n";
  }
  return dir;
}

// The lines of "What differs" that name the estimation basis.
std::vector<std::string> BasisLines(const SweepDiff& diff) {
  std::vector<std::string> lines;
  for (const std::string& d : diff.differs) {
    if (d.rfind("estimation basis", 0) == 0) lines.push_back(d);
  }
  return lines;
}

const MetricDiff& Metric(const SweepDiff& diff, const std::string& name) {
  for (const MetricDiff& m : diff.metrics) {
    if (m.name == name) return m;
  }
  throw std::runtime_error("no metric " + name);
}

SweepDiff Diff(const std::string& a, const std::string& b) {
  SweepDiffOptions options;
  options.a_dir = a;
  options.b_dir = b;
  return CompareSweeps(options);
}

// The one "What differs" line naming the basis of runs `a` against runs `b` (written under the
// names given); empty, with a test failure, when there is not exactly one.
std::string OneBasisLine(const std::string& a_name, const std::vector<BasisRun>& a,
                         const std::string& b_name, const std::vector<BasisRun>& b) {
  const std::vector<std::string> lines =
      BasisLines(Diff(WriteRuns(a_name, a), WriteRuns(b_name, b)));
  if (lines.size() == 1) return lines[0];
  ADD_FAILURE() << lines.size() << " basis lines for " << a_name << " vs " << b_name;
  return "";
}

// Whether `line` holds `text`, showing the line when it does not.
::testing::AssertionResult Holds(const std::string& line, const std::string& text) {
  if (line.find(text) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << text << "' not in: " << line;
}

TEST(SweepDiffBasisTest, ReadsTheBasisEachRunRecords) {
  EXPECT_EQ(*EstimationBasis(Json{{"camera", "ground_truth"}}), "ground truth");
  EXPECT_EQ(*EstimationBasis(Json{{"camera", "render"}}), "estimate, rendered camera");
  EXPECT_EQ(*EstimationBasis(Json{{"camera", "analytic"}}), "estimate, analytic camera");
  EXPECT_EQ(*EstimationBasis(Json{{"camera", "mocap"}, {"team", {{"vehicle_state", "onboard"}}}}),
            "estimate, vehicle state onboard");
  EXPECT_EQ(*EstimationBasis(Json{{"camera", "ground_truth"}, {"team", Json::object()}}),
            "ground truth");
  EXPECT_FALSE(EstimationBasis(Json()));                    // a dead worker's record
  EXPECT_FALSE(EstimationBasis(Json{{"crashed", false}}));  // an older hpa's metrics
}

// The README's unfair pairing: A on the true state, B on estimates with the analytic camera.
// Named, with the pair count and a warning; the same basis on both sides adds no line.
TEST(SweepDiffBasisTest, ADifferentBasisIsNamedWithAWarning) {
  BasisRun truth, estimate;
  truth.camera = "ground_truth";
  const std::string a = WriteRuns("truth", std::vector<BasisRun>(6, truth));
  const std::string b = WriteRuns("estimate", std::vector<BasisRun>(6, estimate));
  const std::vector<std::string> lines = BasisLines(Diff(a, b));
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_TRUE(
      Holds(lines[0], "ground truth (A) vs estimate, analytic camera (B), in 6 of 6 pairs"));
  EXPECT_TRUE(Holds(lines[0], "WARNING"));
  EXPECT_TRUE(Holds(lines[0], "--set estimation.ground_truth=false"));
  EXPECT_TRUE(BasisLines(Diff(b, b)).empty());
  EXPECT_TRUE(BasisLines(Diff(a, a)).empty());
}

// The camera kind and a team's vehicle state are part of the basis (a stack's declining the
// rendered frames is noted without a warning); a pair with a run error is not compared (its
// metrics may be missing), and a side that records no basis is said to.
TEST(SweepDiffBasisTest, CameraTeamStateRunErrorsAndOldRecords) {
  BasisRun analytic, render;
  render.camera = "render";
  std::vector<BasisRun> b(4, render);
  b[0].run_error = true;
  b[0].metrics_written = false;  // a dead worker: no metrics
  EXPECT_TRUE(Holds(OneBasisLine("analytic", std::vector<BasisRun>(4, analytic), "render", b),
                    "analytic camera (A) vs estimate, rendered camera (B), in 3 of 3"));

  BasisRun mocap, onboard;
  mocap.camera = onboard.camera = "mocap";
  mocap.vehicle_state = "motion_capture";
  onboard.vehicle_state = "onboard";
  EXPECT_TRUE(Holds(OneBasisLine("mocap", std::vector<BasisRun>(3, mocap), "onboard",
                                 std::vector<BasisRun>(3, onboard)),
                    "vehicle state motion_capture (A) vs estimate, vehicle state onboard"));

  // a stack that declared it uses no pixels was offered the same rendered camera: no warning
  BasisRun no_pixels;
  no_pixels.camera = "none";
  const std::string declined = OneBasisLine("render_all", std::vector<BasisRun>(3, render),
                                            "no_pixels", std::vector<BasisRun>(3, no_pixels));
  EXPECT_TRUE(Holds(declined, "rendered camera (A) vs estimate, no camera frames"));
  EXPECT_FALSE(Holds(declined, "WARNING"));

  const std::vector<std::string> old = DescribeBasisDifferences(
      {{std::nullopt, std::string("ground truth")}, {std::nullopt, std::string("ground truth")}});
  ASSERT_EQ(old.size(), 1u);
  EXPECT_TRUE(Holds(old[0], "not recorded in A's runs (2)"));
}

// B's runs: 3 never flew (a run error, expect failed with its cause), 2 crashed, the rest as A's.
// Every metric, every rate included, leaves the run-error pairs out as run errors, never as
// crashes; the crash rate counts the crashes; expect_failure_rate counts only the runs that flew
// (the crashes' failed verdicts), never the run errors' verdicts.
TEST(SweepDiffBasisTest, RatesCountRunsWithoutARunErrorAndErrorsAreNotCrashes) {
  std::vector<BasisRun> a(20), b(20);
  for (int i = 0; i < 3; ++i) {
    b[i].run_error = true;
    b[i].expect_passed = false;
  }
  for (int i = 3; i < 5; ++i) {
    b[i].crashed = true;
    b[i].expect_passed = false;
  }
  const SweepDiff diff = Diff(WriteRuns("rates_a", a), WriteRuns("rates_b", b));
  EXPECT_EQ(diff.runs_paired, 20);
  for (const char* rate : {"crash_rate", "expect_failure_rate"}) {
    const MetricDiff& m = Metric(diff, rate);
    EXPECT_EQ(m.pairs, 17) << rate;
    EXPECT_EQ(m.dropped_run_error, 3) << rate;
    EXPECT_EQ(m.dropped_crashed, 0) << rate;
    EXPECT_NEAR(m.b, 2.0 / 17.0, 1e-12) << rate;  // the two crashes, not the three errors
  }
  const MetricDiff& deviation = Metric(diff, "quad_position_deviation_max_m");
  EXPECT_EQ(deviation.dropped_run_error, 3);
  EXPECT_EQ(deviation.dropped_crashed, 2);
  EXPECT_EQ(deviation.pairs, 15);
  // every left-out pair is counted once: the remainder diff.md reports as run errors is these
  for (const MetricDiff& m : diff.metrics) {
    EXPECT_EQ(
        m.pairs + m.dropped_run_error + m.dropped_crashed + m.dropped_one_side + m.dropped_both,
        diff.runs_paired)
        << m.name;
    EXPECT_EQ(m.dropped_run_error, 3) << m.name;
  }
  // the same runs without the run errors: the rates equal, so run errors never make B "worse"
  EXPECT_NE(Metric(diff, "expect_failure_rate").verdict, "worse");
}

}  // namespace
}  // namespace hpa
