#include "hpa/scenarios/sweep.h"

#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <set>

#include "hpa/models/input_error.h"
#include "models/tests/temp_dir.h"

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
  for (int n : {1, 2, 3, 7}) {
    std::map<int, int> seen;
    for (int k = 1; k <= n; ++k) {
      for (const auto& r : runs) {
        if (r.index % n == k - 1) seen[r.index]++;
      }
    }
    EXPECT_EQ(seen.size(), runs.size());
    for (const auto& [index, count] : seen) EXPECT_EQ(count, 1) << index;
  }
}

TEST(SweepTest, EveryShippedSweepLoadsAndExpands) {
  const std::string dir = std::string(HPA_SOURCE_DIR) + "/scenarios/sweeps/";
  for (const char* name :
       {"impulse_crash_rate.yaml", "model_mismatch.yaml", "perception_noise.yaml", "wind.yaml",
        "throughput.yaml", "throughput_render.yaml"}) {
    SweepSpec spec;
    ASSERT_NO_THROW(spec = LoadSweep(dir + name)) << name;
    EXPECT_GE(ExpandSweep(spec).size(), static_cast<size_t>(spec.runs)) << name;
  }
}

TEST(SweepTest, BadPathsFailBeforeAnythingRuns) {
  EXPECT_THROW(Spec("  events.3.impulse.2: {uniform: [0, 1]}\n"), InputError);
  EXPECT_THROW(Spec("  world.gravity: {uniform: [9, 10]}\n"), InputError);
  EXPECT_THROW(Spec("  controller.type: {grid: [hpa_mpc, pid]}\n"), InputError);
  EXPECT_THROW(Spec("  world.payload_mass: {uniform: [0.1]}\n"), InputError);
  EXPECT_THROW(Spec("  world.payload_mass: {triangle: [0, 1, 2]}\n"), InputError);
}

}  // namespace
}  // namespace hpa
