// A per-vehicle metric is one declaration for one vehicle and for a team: a toy declaration of
// the path `vehicles.tilt_max_deg` read as the worst vehicle's, and a toy expect key registered
// in this file alone, read and checked the same way on a single-vehicle run and on a team run
// flown through the real `hpa run`, and in a sweep's record of each. What is still declared twice
// (the team's own `team_*` rows of the same numbers) is checked to read the same values, so the day
// one of them goes, this test says what the other must give.

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hpa/scenarios/cli.h"
#include "hpa/scenarios/expect_keys.h"
#include "hpa/scenarios/metric_defs.h"
#include "hpa/scenarios/metrics.h"
#include "models/tests/temp_dir.h"

namespace hpa {
namespace {

using Json = nlohmann::json;

// `hpa ARGS...` in this process, its exit code.
int Hpa(std::vector<std::string> args) {
  args.insert(args.begin(), "hpa");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  return HpaMain(static_cast<int>(argv.size()), argv.data());
}

// The toy metric as one line of metric_defs.cc would declare it: every vehicle's largest tilt,
// read as the worst vehicle's wherever the run writes `vehicles` (every run does).
MetricDef ToyTiltMetric() {
  return {"toy_tilt_max_deg",
          "vehicles.tilt_max_deg",
          MetricRead::kLargest,
          "deg",
          Better::kLower,
          1.0,
          false,
          false,
          "toy tilt [deg]",
          "the worst vehicle's largest tilt (test)"};
}

// The toy expect key bounding it, registered once: the same check for one vehicle and a team.
void RegisterToyKeyOnce() {
  if (FindExpectKey("toy_tilt_max") != nullptr) return;
  ExpectKey key{"toy_tilt_max",
                ToyTiltMetric().json_path,
                "metric <= bound",
                "deg",
                "every vehicle's largest tilt, at most (test)",
                1,
                0.0,
                180.0,
                false,
                {}};
  key.check = [](const Metrics& m, const std::vector<double>& bound) {
    std::vector<std::string> failed;
    for (const VehicleMetrics& v : m.vehicles) {
      if (v.tilt_max_deg > bound[0]) failed.push_back("toy_tilt_max: over the bound");
    }
    return failed;
  };
  RegisterExpectKey(key);
}

// A short hover with a sideways push on the (first) vehicle: one vehicle, or a team of two
// carrying a bar; `bound_deg` the toy key's bound.
std::string ScenarioText(bool team, double bound_deg) {
  const std::string expect = "expect: {toy_tilt_max: " + std::to_string(bound_deg) + "}\n";
  if (!team) {
    return "name: toy_single\nduration: 1.0\nworld: {profile: ideal}\n"
           "controller: {type: geometric}\n"
           "estimation: {ground_truth: true, camera: analytic}\n"
           "reference: {type: hover, payload_position: [0, 0, 0.7]}\n"
           "events: [{at: 0.3, type: impulse, body: quadrotor, impulse: [0.3, 0, 0]}]\n" +
           expect;
  }
  return "name: toy_team\nduration: 1.0\nworld: {profile: ideal}\n"
         "controller: {type: cooperative}\n"
         "payload: {mass_kg: 0.2, inertia_kgm2: [1.3e-4, 8.2e-3, 8.2e-3]}\n"
         "vehicles:\n"
         "  - {cable_length_m: 0.5, attach_m: [0.35, 0, 0]}\n"
         "  - {cable_length_m: 0.5, attach_m: [-0.35, 0, 0]}\n"
         "reference: {type: hover, payload_position: [0, 0, 1.0]}\n"
         "events: [{at: 0.3, type: impulse, body: quadrotor, vehicle: 0, impulse: [0.3, 0, 0]}]\n" +
         expect;
}

// Flies the scenario through `hpa run`; its metrics.json, and the exit code in *code.
Json Fly(const std::string& dir, const std::string& name, const std::string& text, int* code) {
  std::ofstream(dir + name + ".yaml") << text;
  *code = Hpa({"run", dir + name + ".yaml", "--out", dir + name, "--quiet"});
  std::ifstream in(dir + name + "/metrics.json");
  return Json::parse(in);
}

// The metrics of the one run of a sweep over the scenario `name` (its runs.jsonl record).
Json SweepRecordMetrics(const std::string& dir, const std::string& name) {
  std::ofstream(dir + name + "_sweep.yaml")
      << "base: " << name << ".yaml\nruns: 1\nvary:\n  duration: {list: [1.0]}\n";
  EXPECT_EQ(
      Hpa({"sweep", dir + name + "_sweep.yaml", "--out", dir + name + "_sweep", "--jobs", "1"}), 0);
  std::ifstream in(dir + name + "_sweep/runs.jsonl");
  std::string line;
  std::getline(in, line);
  return Json::parse(line)["metrics"];
}

// The largest `tilt_max_deg` of the run's `vehicles` entries, read by hand.
double WorstTiltDeg(const Json& m) {
  double worst = 0.0;
  for (const Json& v : m["vehicles"]) worst = std::max(worst, v["tilt_max_deg"].get<double>());
  return worst;
}

TEST(VehicleMetricDeclarationTest, OneDeclarationReadsAndBoundsOneVehicleAndATeam) {
  RegisterToyKeyOnce();
  const std::string dir = TestTempDir();
  for (const bool team : {false, true}) {
    SCOPED_TRACE(team ? "a team of two" : "one vehicle");
    const std::string kind = team ? "team" : "single";
    int code = -1;
    // a loose bound holds: the scenario reader takes the key on both kinds of run
    const Json loose = Fly(dir, kind + "_loose", ScenarioText(team, 90.0), &code);
    EXPECT_EQ(code, 0);
    ASSERT_EQ(loose["vehicles"].size(), team ? 2u : 1u);
    // the one declaration reads the worst vehicle's tilt, which the push made non-zero
    const std::optional<double> toy = ReadMetric(ToyTiltMetric(), loose);
    ASSERT_TRUE(toy.has_value());
    EXPECT_EQ(*toy, WorstTiltDeg(loose));
    EXPECT_GT(*toy, 0.1);
    // and so does the registered declaration of the same path
    EXPECT_EQ(ReadMetric("vehicle_tilt_max_deg", loose), toy);
    // a sweep's record holds its run's metrics.json (the run's own seed): read there the same way
    const Json record = SweepRecordMetrics(dir, kind + "_loose");
    ASSERT_EQ(record["vehicles"].size(), team ? 2u : 1u);
    EXPECT_EQ(ReadMetric(ToyTiltMetric(), record), WorstTiltDeg(record));
    // a tight bound fails with the key's own message, on both kinds of run
    const Json tight = Fly(dir, kind + "_tight", ScenarioText(team, 0.001), &code);
    EXPECT_EQ(code, 1);
    ASSERT_FALSE(tight["expect"]["failed"].empty());
    EXPECT_EQ(tight["expect"]["failed"][0], "toy_tilt_max: over the bound");
    // the team's own declarations of the same numbers (`team.vehicles.*`): the same values on a
    // team, not measured on one vehicle
    for (const auto& [vehicle, team_row] :
         {std::pair<const char*, const char*>{"vehicle_tilt_max_deg", "team_vehicle_tilt_max_deg"},
          {"cable_tension_max_N", "team_cable_tension_max_N"}}) {
      SCOPED_TRACE(team_row);
      if (team) {
        EXPECT_EQ(ReadMetric(team_row, loose), ReadMetric(vehicle, loose));
      } else {
        EXPECT_FALSE(ReadMetric(team_row, loose).has_value());
        EXPECT_TRUE(ReadMetric(vehicle, loose).has_value());
      }
    }
  }
}

}  // namespace
}  // namespace hpa
