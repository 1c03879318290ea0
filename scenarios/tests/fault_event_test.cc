// The fault event: its keys come from the world's fault declaration, bad input names the key and
// the valid values, a run writes each fault's recovery metrics (null where they do not apply),
// and the same seed gives the same faulty run.

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/scenarios/metrics.h"
#include "hpa/scenarios/runner.h"
#include "hpa/scenarios/scenario.h"
#include "hpa/sim/faults.h"
#include "models/tests/temp_dir.h"

namespace hpa {
namespace {

// A short onboard hover (analytic camera) with `events`.
Scenario Load(const std::string& events, double duration_s = 0.3) {
  const std::string path = TestTempDir() + "fault_events.yaml";
  std::ofstream(path) << "name: faults\nduration: " << duration_s
                      << "\ncontroller: {type: hpa_mpc}\n"
                         "estimation: {ground_truth: false, camera: analytic}\nevents:\n"
                      << events;
  return LoadScenario(path);
}

// The InputError text of loading `events`, or "" if it loads.
std::string ErrorOf(const std::string& events) {
  try {
    Load(events);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(FaultEventTest, EveryDeclaredModeParsesWithItsRequiredKeys) {
  for (const sim::FaultComponentDecl& c : sim::FaultComponents()) {
    for (const sim::FaultModeDecl& m : c.modes) {
      std::string event = "  - {at: 0.1, type: fault, component: " + c.name + ", mode: " + m.name;
      for (const sim::FaultKeyDecl& k : m.keys) {
        if (k.fallback) continue;
        const double v = k.integer ? k.min : 0.5 * (k.min + k.max);
        event += ", " + k.key + ": " +
                 (k.vector != nullptr ? "[" + std::to_string(v) + ", 0, 0]" : std::to_string(v));
      }
      event += m.has_duration ? ", duration: 0.1}\n" : "}\n";
      EXPECT_EQ(ErrorOf(event), "") << event;
    }
  }
}

TEST(FaultEventTest, BadInputNamesTheKeyAndTheValidValues) {
  const std::string component =
      ErrorOf("  - {at: 0.1, type: fault, component: lidar, mode: off}\n");
  EXPECT_NE(component.find("events.0.component"), std::string::npos) << component;
  for (const sim::FaultComponentDecl& c : sim::FaultComponents()) {
    EXPECT_NE(component.find(c.name), std::string::npos) << c.name << ": " << component;
  }
  const std::string mode = ErrorOf("  - {at: 0.1, type: fault, component: motor, mode: stuck}\n");
  EXPECT_NE(mode.find("events.0.mode"), std::string::npos) << mode;
  EXPECT_NE(mode.find("loss | off"), std::string::npos) << mode;
  const std::string range =
      ErrorOf("  - {at: 0.1, type: fault, component: motor, mode: loss, motor: 0, loss: 1.5}\n");
  EXPECT_NE(range.find("events.0.loss"), std::string::npos) << range;
  EXPECT_NE(ErrorOf("  - {at: 0.1, type: fault, component: motor, mode: off, motor: 4}\n"), "");
  EXPECT_NE(ErrorOf("  - {at: 0.1, type: fault, component: motor, mode: off, motor: 0.5}\n"), "");
  // another mode's key, and a duration on an instant
  EXPECT_NE(ErrorOf("  - {at: 0.1, type: fault, component: vio, mode: off, offset: [1, 0, 0]}\n"),
            "");
  EXPECT_NE(ErrorOf("  - {at: 0.1, type: fault, component: gripper, mode: early, duration: 1}\n"),
            "");
  EXPECT_NE(ErrorOf("  - {at: 0.1, type: fault, component: vio}\n"), "");
}

TEST(FaultEventTest, ARunWritesEachFaultsRecoveryWithNullWhereItDoesNotApply) {
  const Params params = LoadParams(std::string(HPA_SOURCE_DIR) + "/models/params.yaml");
  const Scenario scenario = Load(
      "  - {at: 0.2, type: fault, component: vio, mode: off, duration: 0.2}\n"
      "  - {at: 0.5, type: fault, component: payload_camera, mode: off}\n",
      1.0);
  const RunResult run = RunScenario(scenario, params, RunOptions{});
  const nlohmann::json j = nlohmann::json::parse(MetricsToJson(run.metrics));
  ASSERT_EQ(j["faults"].size(), 2u);
  const nlohmann::json& vio = j["faults"][0];
  EXPECT_EQ(vio["component"], "vio");
  EXPECT_DOUBLE_EQ(vio["end_s"].get<double>(), 0.4);
  EXPECT_DOUBLE_EQ(vio["span_end_s"].get<double>(), 0.5);  // the camera fault's start
  EXPECT_FALSE(vio["payload_lost"].get<bool>());
  EXPECT_TRUE(vio["payload_back_in_view_s"].is_null());  // never lost: does not apply, not 0
  const nlohmann::json& camera = j["faults"][1];
  EXPECT_TRUE(camera["end_s"].is_null());  // to the end of the run
  EXPECT_TRUE(camera["payload_lost"].get<bool>());
  EXPECT_TRUE(camera["payload_back_in_view_s"].is_null());  // never back
  EXPECT_EQ(j["fault_recovery"]["unrecovered"], 1);

  // the same seed, the same faulty run
  const RunResult again = RunScenario(scenario, params, RunOptions{});
  EXPECT_EQ(nlohmann::json::parse(MetricsToJson(again.metrics))["faults"], j["faults"]);
}

}  // namespace
}  // namespace hpa
