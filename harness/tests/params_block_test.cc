// A scenario's params: block changes the flight code's model and the simulated world alike;
// world.cable_length still changes the world alone (model mismatch).
#include <gtest/gtest.h>

#include <fstream>

#include "hpa/models/params.h"
#include "hpa/scenarios/runner.h"
#include "hpa/scenarios/scenario.h"
#include "models/tests/temp_dir.h"

namespace hpa {
namespace {

// Mean true cable length and mean reference quad-payload distance over the taut rows of a run.
void CableLengths(const std::string& extra, double* true_m, double* model_m) {
  const std::string path = TestTempDir() + "params_block.yaml";
  std::ofstream(path) << "name: params_block\nduration: 1.0\nestimation: {camera: analytic, "
                         "ground_truth: true}\n"
                      << extra;
  const Scenario s = LoadScenario(path);
  const RunResult r = RunScenario(s, LoadParams(DefaultParamsPath()), RunOptions{});
  ASSERT_FALSE(r.metrics.crashed);
  ASSERT_FALSE(r.rows.empty());
  double sum_true = 0.0, sum_model = 0.0;
  for (const LogRow& row : r.rows) {
    sum_true += (row.truth.p_WQ_W - row.truth.p_WL_W).norm();
    sum_model += (row.reference.p_WQ_W - row.reference.p_WL_W).norm();
  }
  *true_m = sum_true / r.rows.size();
  *model_m = sum_model / r.rows.size();
}

TEST(ParamsBlockTest, ChangesTheWorldAndTheFlightModelAlike) {
  double true_m = 0.0, model_m = 0.0;
  CableLengths("world: {profile: ideal}\nparams: {cable: {length_m: 0.8}}\n", &true_m, &model_m);
  // the tendon stretches by its contact softness (measured under 5 mm): 1 cm bound
  EXPECT_NEAR(true_m, 0.8, 0.01);
  EXPECT_NEAR(model_m, 0.8, 1e-9);
  // world.cable_length: the world alone
  CableLengths("world: {profile: ideal, cable_length: 0.8}\n", &true_m, &model_m);
  EXPECT_NEAR(true_m, 0.8, 0.01);
  EXPECT_NEAR(model_m, 0.5, 1e-9);
}

TEST(ParamsBlockTest, ScenarioParamsLeavesOtherValues) {
  const std::string path = TestTempDir() + "params_block2.yaml";
  std::ofstream(path) << "name: p\nduration: 1.0\nparams: {payload: {mass_kg: 0.2}}\n";
  const Params base = LoadParams(DefaultParamsPath());
  const Params p = ScenarioParams(LoadScenario(path), base);
  EXPECT_EQ(p.payload_mass_kg, 0.2);
  EXPECT_EQ(p.cable_length_m, base.cable_length_m);
  EXPECT_EQ(p.k_f_N_per_radps2, base.k_f_N_per_radps2);
}

}  // namespace
}  // namespace hpa
