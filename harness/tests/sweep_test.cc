#include "hpa/scenarios/sweep.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "hpa/models/input_error.h"
#include "models/tests/temp_dir.h"
#include "harness/sweeps/src/sweep_internal.h"

namespace hpa {
namespace {

std::string Write(const std::string& name, const std::string& text) {
  const std::string path = TestTempDir() + name;
  std::ofstream(path) << text;
  return path;
}

const char* kBase = R"(name: base
duration: 1.0
controller: {type: hpa_mpc}
events:
  - {at: 0.5, type: impulse, body: payload, impulse: [0, 0, 0.1]}
)";

SweepSpec Spec(const std::string& vary, int runs = 50) {
  Write("base.yaml", kBase);
  return LoadSweep(Write("sweep.yaml", "base: base.yaml\nruns: " + std::to_string(runs) +
                                           "\nseed: 7\nvary:\n" + vary));
}

double Value(const SweepRun& r, const std::string& path) {
  for (const auto& [p, v] : r.values) {
    if (p == path) return std::stod(v);
  }
  ADD_FAILURE() << "no value for " << path;
  return 0;
}

TEST(SweepTest, UniformAndNormalDraws) {
  const auto runs =
      ExpandSweep(Spec("  events.0.impulse.2: {uniform: [0.2, 0.6]}\n"
                       "  world.payload_mass: {normal: [0.1, 0.01]}\n",
                       400));
  ASSERT_EQ(runs.size(), 400u);
  double sum = 0, sum_sq = 0;
  for (const auto& r : runs) {
    const double v = Value(r, "events.0.impulse.2");
    EXPECT_GE(v, 0.2);
    EXPECT_LE(v, 0.6);
    const double m = Value(r, "world.payload_mass");
    sum += m;
    sum_sq += m * m;
  }
  const double mean = sum / runs.size();
  const double sd = std::sqrt(sum_sq / runs.size() - mean * mean);
  // 400 draws: standard error of the mean 0.0005, of the s.d. ~0.00035; bounds are ~4 sigma
  EXPECT_NEAR(mean, 0.1, 0.002);
  EXPECT_NEAR(sd, 0.01, 0.0015);
}

TEST(SweepTest, GridMultipliesDrawsAndPairsThem) {
  const auto runs =
      ExpandSweep(Spec("  events.0.impulse.2: {uniform: [0.2, 0.6]}\n"
                       "  controller.type: {grid: [hpa_mpc, nonhybrid_mpc]}\n",
                       10));
  ASSERT_EQ(runs.size(), 20u);
  for (int d = 0; d < 10; ++d) {
    const SweepRun& a = runs[2 * d];
    const SweepRun& b = runs[2 * d + 1];
    EXPECT_EQ(a.draw, d);
    EXPECT_EQ(b.draw, d);
    EXPECT_EQ(a.seed, b.seed);  // paired: same seed and same draws for both controllers
    EXPECT_EQ(Value(a, "events.0.impulse.2"), Value(b, "events.0.impulse.2"));
    EXPECT_EQ(a.values.back().second, "hpa_mpc");
    EXPECT_EQ(b.values.back().second, "nonhybrid_mpc");
  }
}

TEST(SweepTest, ListCyclesOverDraws) {
  const auto runs = ExpandSweep(Spec("  events.0.impulse.2: {list: [0.1, 0.2, 0.3]}\n", 6));
  std::vector<double> got;
  for (const auto& r : runs) got.push_back(Value(r, "events.0.impulse.2"));
  EXPECT_EQ(got, (std::vector<double>{0.1, 0.2, 0.3, 0.1, 0.2, 0.3}));
}

TEST(SweepTest, SeedsAreStable) {
  const auto a = ExpandSweep(Spec("  events.0.impulse.2: {uniform: [0.2, 0.6]}\n", 20));
  const auto b = ExpandSweep(Spec("  events.0.impulse.2: {uniform: [0.2, 0.6]}\n", 40));
  // the first 20 draws do not change when the sweep grows
  for (int i = 0; i < 20; ++i) {
    EXPECT_EQ(a[i].seed, b[i].seed);
    EXPECT_EQ(a[i].values, b[i].values);
  }
  std::set<unsigned long> seeds;
  for (const auto& r : b) seeds.insert(r.seed);
  EXPECT_EQ(seeds.size(), b.size());
}

TEST(SweepTest, ShardsPartitionTheRuns) {
  const auto runs = ExpandSweep(Spec("  controller.type: {grid: [hpa_mpc, nonhybrid_mpc]}\n", 13));
  for (int n : {1, 2, 3, 7, 40}) {
    std::map<int, int> seen;
    for (int k = 1; k <= n; ++k) {
      for (const auto& r : SelectShard(runs, k, n)) seen[r.index]++;
    }
    EXPECT_EQ(seen.size(), runs.size()) << n << " shards";
    for (const auto& [index, count] : seen) EXPECT_EQ(count, 1) << index;
  }
  // shard sizes differ by at most one run (a job array's tasks take about as long)
  EXPECT_EQ(SelectShard(runs, 1, 3).size(), 9u);
  EXPECT_EQ(SelectShard(runs, 3, 3).size(), 8u);
}

TEST(SweepTest, EveryDrawIsValidatedNotOnlyTheFirst) {
  // payload_mass must be > 0: with 30 draws from [-1, 1] some are negative whatever the first
  try {
    Spec("  world.payload_mass: {uniform: [-1.0, 1.0]}\n", 30);
    ADD_FAILURE() << "a sweep with invalid draws was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("is not a valid scenario"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("world.payload_mass="), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(Spec("  world.payload_mass: {uniform: [0.1, 1.0]}\n", 30));
}

TEST(SweepTest, ABadBaseWithoutVaryIsNamed) {
  // found by the fuzzer: a sweep with no `vary` whose base cannot be loaded
  Write("no_vary.yaml", "base: missing_base.yaml\nruns: 4\n");
  try {
    LoadSweep(TestTempDir() + "no_vary.yaml");
    ADD_FAILURE() << "a sweep on a missing base was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("key 'base'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("missing_base.yaml"), std::string::npos) << e.what();
  }
}

TEST(SweepTest, WilsonIntervalMatchesReferenceValues) {
  // reference values from the closed form (Wilson 1927, z = 1.96), e.g. statsmodels'
  // proportion_confint(k, n, method="wilson"): 0/10 -> [0, 0.2775], 1/6 -> [0.0301, 0.5635],
  // 5/10 -> [0.2366, 0.7634], 20/20 -> [0.8389, 1]
  const auto near = [](std::pair<double, double> got, double lo, double hi) {
    EXPECT_NEAR(got.first, lo, 5e-4);
    EXPECT_NEAR(got.second, hi, 5e-4);
  };
  near(sweep::Wilson(0, 10), 0.0, 0.2775);
  near(sweep::Wilson(1, 6), 0.0301, 0.5635);
  near(sweep::Wilson(5, 10), 0.2366, 0.7634);
  near(sweep::Wilson(20, 20), 0.8389, 1.0);
  near(sweep::Wilson(0, 0), 0.0, 1.0);  // no run: no information
}

TEST(SweepTest, BinsAreDistinctValuesOrSixEqualBins) {
  const auto few = sweep::MakeBins({0.3, 0.1, 0.3, 0.2});
  ASSERT_EQ(few.size(), 3u);
  EXPECT_EQ(few[0], std::make_pair(0.1, 0.1));
  EXPECT_EQ(sweep::BinOf(few, 0.2), 1);
  std::vector<double> many;
  for (int i = 0; i <= 12; ++i) many.push_back(1.0 + 0.5 * i);  // 1 .. 7
  const auto six = sweep::MakeBins(many);
  ASSERT_EQ(six.size(), 6u);
  EXPECT_DOUBLE_EQ(six.front().first, 1.0);
  EXPECT_DOUBLE_EQ(six.back().second, 7.0);
  EXPECT_EQ(sweep::BinOf(six, 1.0), 0);
  EXPECT_EQ(sweep::BinOf(six, 2.0), 0);  // a shared edge goes to the lower bin
  EXPECT_EQ(sweep::BinOf(six, 2.01), 1);
  EXPECT_EQ(sweep::BinOf(six, 7.0), 5);
  EXPECT_EQ(sweep::BinOf(six, 99.0), 5);
}

TEST(SweepTest, EveryShippedSweepLoadsAndExpands) {
  const std::string dir = std::string(HPA_SOURCE_DIR) + "/scenarios/sweeps/";
  int sweeps = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".yaml") continue;
    const std::string name = entry.path().filename().string();
    SweepSpec spec;
    ASSERT_NO_THROW(spec = LoadSweep(entry.path().string())) << name;
    EXPECT_GE(ExpandSweep(spec).size(), static_cast<size_t>(spec.runs)) << name;
    ++sweeps;
  }
  EXPECT_GE(sweeps, 7);
}

TEST(SweepTest, BadPathsFailBeforeAnythingRuns) {
  EXPECT_THROW(Spec("  events.3.impulse.2: {uniform: [0, 1]}\n"), InputError);
  EXPECT_THROW(Spec("  world.gravity: {uniform: [9, 10]}\n"), InputError);
  EXPECT_THROW(Spec("  controller.type: {grid: [hpa_mpc, pid]}\n"), InputError);
  EXPECT_THROW(Spec("  world.payload_mass: {uniform: [0.1]}\n"), InputError);
  EXPECT_THROW(Spec("  world.payload_mass: {triangle: [0, 1, 2]}\n"), InputError);
}

}  // namespace
// The summary lists the runs the estimator lost although nothing crashed: a whole flight read
// slack (mode accuracy 0.067 among runs at 0.99-1.00), and one with 5 filter restarts where the
// rest have none; a run 0.03 below the median is not listed (below the 0.05 floor).
TEST(SweepOutlierTest, ListsRunsWhoseModeAccuracyOrResetsStandOut) {
  std::vector<sweep::Record> records(12);
  for (size_t i = 0; i < records.size(); ++i) {
    records[i].run = static_cast<int>(i);
    records[i].controller = "hpa_mpc";
    records[i].mode_accuracy = 0.99 + 0.001 * static_cast<double>(i % 5);
  }
  records[3].mode_accuracy = 0.067;
  records[5].mode_accuracy = 0.962;
  records[7].estimator_restarts = 5;
  records[9].error = true;  // errors are not judged
  records[9].mode_accuracy = 0.0;
  const std::vector<sweep::Outlier> outliers = sweep::FindOutliers(records);
  ASSERT_EQ(outliers.size(), 2u);
  EXPECT_EQ(outliers[0].record->run, 3);
  EXPECT_EQ(outliers[0].metric, "mode_accuracy");
  EXPECT_NEAR(outliers[0].median, 0.992, 0.002);  // the runs at 0.990-0.994
  EXPECT_EQ(outliers[1].record->run, 7);
  EXPECT_EQ(outliers[1].metric, "estimator_restarts");
}

// Outliers are judged within their grid cell: a cell whose detector noise is 30 times the other's
// restarts the estimator 8-13 times in every run, and none of its runs is listed against the
// quiet cell's median of 0; a run of 12 restarts in the quiet cell still is.
TEST(SweepOutlierTest, ComparesWithinEachGridCell) {
  std::vector<sweep::Record> records(20);
  for (size_t i = 0; i < records.size(); ++i) {
    records[i].run = static_cast<int>(i);
    records[i].controller = "hpa_mpc";
    const bool noisy = i % 5 == 0;
    records[i].values = {{"estimation.detector_noise_scale", noisy ? "30" : "1"}};
    records[i].estimator_restarts = noisy ? 8.0 + static_cast<double>(i % 10) : 0.0;
  }
  records[4].estimator_restarts = 12;
  const std::vector<sweep::Outlier> outliers =
      sweep::FindOutliers(records, {"estimation.detector_noise_scale"});
  ASSERT_EQ(outliers.size(), 1u);
  EXPECT_EQ(outliers[0].record->run, 4);
  EXPECT_EQ(outliers[0].metric, "estimator_restarts");
  // pooled (no grid keys) the noisy cell's every run stands out as well
  EXPECT_EQ(sweep::FindOutliers(records).size(), 5u);
}

// The summary groups runs by every grid variable, bins the drawn quantity over its declared
// range (not the range the draws covered) and labels it with its `label:`.
TEST(SweepSummaryTest, GroupsByGridVariablesAndBinsOverTheDeclaredRange) {
  SweepSpec spec;
  VarySpec mass;
  mass.path = "world.payload_mass";
  mass.kind = VarySpec::Kind::kUniform;
  mass.a = 0.05;
  mass.b = 0.35;
  mass.label = "payload mass [kg]";
  VarySpec cue;
  cue.path = "estimation.slack_tension_cue";
  cue.kind = VarySpec::Kind::kGrid;
  cue.values = {"true", "false"};
  spec.vary = {mass, cue};
  spec.runs = 10;
  std::vector<sweep::Record> records;
  for (int i = 0; i < 20; ++i) {
    sweep::Record r;
    r.run = i;
    r.controller = "hpa_mpc";
    // draws cover 0.11-0.29 only
    r.values = {{"world.payload_mass", std::to_string(0.11 + 0.02 * (i / 2))},
                {"estimation.slack_tension_cue", i % 2 == 0 ? "true" : "false"}};
    r.line = "{}";
    records.push_back(r);
  }
  const std::string dir = TestTempDir() + "summary";
  std::filesystem::create_directories(dir);
  sweep::WriteSummary(records, dir, &spec);
  const nlohmann::json summary = nlohmann::json::parse(std::ifstream(dir + "/summary.json"));
  EXPECT_EQ(summary["main_varied_label"], "payload mass [kg]");
  EXPECT_EQ(summary["grouped_by"].size(), 2u);
  ASSERT_TRUE(summary["controllers"].contains("hpa_mpc, estimation.slack_tension_cue=true"));
  ASSERT_TRUE(summary["controllers"].contains("hpa_mpc, estimation.slack_tension_cue=false"));
  const auto& bins = summary["controllers"]["hpa_mpc, estimation.slack_tension_cue=true"]["bins"];
  ASSERT_EQ(bins.size(), 6u);
  EXPECT_NEAR(bins.front()["lo"].get<double>(), 0.05, 1e-12);
  EXPECT_NEAR(bins.back()["hi"].get<double>(), 0.35, 1e-12);
  EXPECT_EQ(bins.front()["runs"].get<int>(), 0);  // nothing drawn in 0.05-0.10: an empty bin
}

TEST(SweepSummaryTest, AGroupWithNoFinishedRunHasNoCrashRate) {
  // every run an error: the crash rate is unknown (null, "-"), not a perfect-looking 0.000
  std::vector<sweep::Record> records;
  for (int i = 0; i < 3; ++i) {
    sweep::Record r;
    r.run = i;
    r.controller = "hpa_mpc";
    r.error = true;
    r.line = "{}";
    records.push_back(r);
  }
  const std::string dir = TestTempDir() + "summary_errors";
  std::filesystem::create_directories(dir);
  sweep::WriteSummary(records, dir, nullptr);
  const nlohmann::json summary = nlohmann::json::parse(std::ifstream(dir + "/summary.json"));
  EXPECT_TRUE(summary["controllers"]["hpa_mpc"]["crash_rate"].is_null());
  std::ifstream md_file(dir + "/summary.md");
  const std::string md((std::istreambuf_iterator<char>(md_file)), std::istreambuf_iterator<char>());
  EXPECT_EQ(md.find("0.000 ["), std::string::npos) << md;
  EXPECT_NE(md.find("| hpa_mpc | 0 | 3 | 0 | - ["), std::string::npos) << md;  // runs, errors
}

}  // namespace hpa
