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

// A log of control steps every 0.1 s from 0 to 2.9 s with one payload-speed reset at 0.45 s,
// one cable-length reset at 1.25 s and one at 2.55 s (counts by cause so far, as the stack
// reports them), or without counts by cause.
std::vector<LogRow> RowsWithResets(bool by_cause) {
  std::vector<LogRow> rows;
  for (int k = 0; k < 30; ++k) {
    LogRow row;
    row.time_s = 0.1 * k;
    if (by_cause) {
      EstimatorHealthResets resets;
      resets.payload_speed = row.time_s > 0.45 ? 1 : 0;
      resets.cable_length = (row.time_s > 1.25 ? 1 : 0) + (row.time_s > 2.55 ? 1 : 0);
      row.estimator_health_resets = resets;
    }
    rows.push_back(row);
  }
  return rows;
}

TEST(FaultEventTest, EachFaultCountsTheHealthResetsByCauseInItsSpan) {
  MetricsInputs in;
  in.rows = RowsWithResets(true);
  // the first fault's span ends where the second starts; the second's at the end of the log
  in.faults = {{0, "vio", "off", 0.3, 0.7, 0.1}, {1, "imu", "bias", 1.0, 1.5, 0.1}};
  Metrics m;
  ComputeMetrics(in, &m);
  ASSERT_EQ(m.faults.size(), 2u);
  ASSERT_TRUE(m.faults[0].health_resets.has_value());
  EXPECT_EQ(m.faults[0].health_resets->payload_speed, 1);
  EXPECT_EQ(m.faults[0].health_resets->cable_length, 0);
  ASSERT_TRUE(m.faults[1].health_resets.has_value());
  EXPECT_EQ(m.faults[1].health_resets->payload_speed, 0);
  EXPECT_EQ(m.faults[1].health_resets->cable_length, 2);
  EXPECT_EQ(m.faults[1].health_resets->Total(), 2);
  const nlohmann::json j = nlohmann::json::parse(MetricsToJson(m));
  EXPECT_EQ(j["faults"][1]["health_resets"]["cable_length"], 2);
  EXPECT_EQ(j["faults"][1]["health_resets"]["quad_non_finite"], 0);

  // a log without counts by cause (a stack that does not report them): null, not 0
  in.rows = RowsWithResets(false);
  ComputeMetrics(in, &m);
  EXPECT_FALSE(m.faults[0].health_resets.has_value());
  EXPECT_TRUE(nlohmann::json::parse(MetricsToJson(m))["faults"][0]["health_resets"].is_null());
}

TEST(FaultEventTest, ADistractorsFrameTallyReachesItsFaultEvent) {
  MetricsInputs in;
  in.rows = RowsWithResets(false);
  in.faults = {{0, "payload_camera", "off", 0.5, 1.0, 0.1},
               {1, "payload_camera", "distractor", 0.5, 2.0, 0.1}};
  Metrics m;
  ComputeMetrics(in, &m);
  sim::FaultFrameTally off;  // the camera-off fault injected first: no distractor counts
  off.start_s = 0.5;
  sim::FaultFrameTally d;
  d.start_s = 0.5;
  d.distractor = true;
  d.frames = 45;
  d.drawn_frames = 15;
  d.in_image_frames = 12;
  d.detections = 40;
  d.detections_on_distractor = 10;
  ASSERT_TRUE(AddFaultFrameTallies({off, d}, &m));
  EXPECT_FALSE(m.faults[0].false_detection_rate.has_value());  // not a distractor: null
  EXPECT_DOUBLE_EQ(*m.faults[1].distractor_drawn_fraction, 15.0 / 45.0);
  EXPECT_DOUBLE_EQ(*m.faults[1].distractor_in_image_fraction, 12.0 / 45.0);
  EXPECT_EQ(*m.faults[1].false_detections, 10);
  EXPECT_DOUBLE_EQ(*m.faults[1].false_detection_rate, 0.25);
  const nlohmann::json j = nlohmann::json::parse(MetricsToJson(m));
  EXPECT_DOUBLE_EQ(j["fault_recovery"]["false_detection_rate"].get<double>(), 0.25);
  EXPECT_TRUE(j["faults"][0]["false_detection_rate"].is_null());
}

TEST(FaultEventTest, AFlickeringDistractorsDrawnShareFollowsItsRate) {
  // the rendered hover with the payload's twin beside it, drawn in 30 % of the frames
  const Params params = LoadParams(std::string(HPA_SOURCE_DIR) + "/models/params.yaml");
  const std::string path = TestTempDir() + "flicker.yaml";
  std::ofstream(path) << "name: flicker\nduration: 1.0\ncontroller: {type: hpa_mpc}\n"
                         "reference: {type: hover, payload_position: [0, 0, 0.7]}\n"
                         "estimation: {ground_truth: false, camera: render}\n"
                         "events:\n  - {at: 0.0, type: fault, component: payload_camera, mode: "
                         "distractor, position: [0.15, 0, 0.7], visible_rate: 0.3}\n";
  const RunResult run = RunScenario(LoadScenario(path), params, RunOptions{});
  ASSERT_EQ(run.metrics.faults.size(), 1u);
  const FaultRecovery& r = run.metrics.faults[0];
  ASSERT_TRUE(r.distractor_drawn_fraction.has_value());
  // 31 frames: the binomial share's standard deviation is 0.082; 3 of them
  EXPECT_NEAR(*r.distractor_drawn_fraction, 0.3, 0.25);
  EXPECT_EQ(*r.distractor_in_image_fraction, *r.distractor_drawn_fraction);  // beside it
  ASSERT_TRUE(r.false_detections.has_value());
  EXPECT_LE(*r.false_detections, *r.detections);
}

}  // namespace
}  // namespace hpa
