#include "hpa/scenarios/metric_defs.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <set>

#include "hpa/scenarios/expect_keys.h"
#include "hpa/scenarios/metrics.h"

namespace hpa {
namespace {

// A metrics.json of a run that flew (control steps, frames, one re-taut and one fault event it
// recovered from).
nlohmann::json FlownMetrics() {
  Metrics m;
  m.control_steps = 100;
  m.vehicles.resize(1);
  m.vehicles[0].cable_tension_max_N = 12.5;
  m.vehicles[0].tilt_max_deg = 7.0;
  m.camera_frames = 30;
  m.payload_rmse_m = Eigen::Vector3d(0.03, 0.04, 0.12);
  m.quad_position_deviation_max_m = 0.25;
  m.mode_accuracy = 0.9;
  m.retaut_count = 1;
  m.retaut_quad_vz_min_mps = -0.7;
  m.retaut_peak_body_rate_radps = 1.2;
  m.slack_detection_latency_max_s = 0.02;
  m.mpc_solve_ms.median = 0.3;
  FaultRecovery fault;
  fault.health_flag_s = 0.1;
  fault.payload_lost = true;
  fault.payload_back_in_view_s = 0.2;
  fault.tracking_left_bound = true;
  fault.tracking_recovered_s = 0.5;
  fault.tracking_error_max_m = 0.15;
  fault.estimate_error_max_m = 0.05;
  fault.false_detection_rate = 0.02;
  m.faults = {fault};
  return nlohmann::json::parse(MetricsToJson(m));
}

// The metrics.json of a flown team run of two vehicles (the team metrics measured).
nlohmann::json FlownTeamMetrics() {
  Metrics m;
  m.control_steps = 100;
  m.team = TeamMetrics();
  m.vehicles.resize(2);
  m.team->min_vehicle_separation_m = 0.7;
  return nlohmann::json::parse(MetricsToJson(m));
}

TEST(MetricDefsTest, EveryMetricIsReadFromTheMetricsJsonTheRunnerWrites) {
  const nlohmann::json j = FlownMetrics();
  const nlohmann::json team = FlownTeamMetrics();
  for (const MetricDef& def : MetricDefs()) {
    // a team's metrics from a team run, every other from the single vehicle's
    const bool of_team = def.json_path.rfind("team.", 0) == 0;
    EXPECT_TRUE(ReadMetric(def, of_team ? team : j).has_value())
        << def.name << " at " << def.json_path;
    EXPECT_FALSE(def.unit.empty()) << def.name;
    EXPECT_FALSE(def.description.empty()) << def.name;
    if (def.compared) {
      EXPECT_GT(def.min_effect, 0.0) << def.name;
    }
  }
  EXPECT_DOUBLE_EQ(*ReadMetric("payload_rmse_norm_m", j), 0.13);
  EXPECT_DOUBLE_EQ(*ReadMetric("quad_position_deviation_max_m", j), 0.25);
  EXPECT_DOUBLE_EQ(*ReadMetric("retaut_quad_vz_min_mps", j), -0.7);
  EXPECT_DOUBLE_EQ(*ReadMetric("slack_detection_latency_max_s", j), 0.02);
  EXPECT_DOUBLE_EQ(*ReadMetric("mpc_solve_median_ms", j), 0.3);
  EXPECT_DOUBLE_EQ(*ReadMetric("cable_tension_max_N", j), 12.5);
  EXPECT_DOUBLE_EQ(*ReadMetric("vehicle_tilt_max_deg", j), 7.0);
  EXPECT_EQ(*ReadMetric("crashed", j), 0.0);
  EXPECT_THROW(ReadMetric("no_such_metric", j), std::logic_error);
}

TEST(MetricDefsTest, WhatARunDidNotMeasureIsNotRead) {
  Metrics unflown;  // ended before its first control step, no re-taut, no frames
  const nlohmann::json j = nlohmann::json::parse(MetricsToJson(unflown));
  EXPECT_FALSE(ReadMetric("quad_position_deviation_max_m", j));
  EXPECT_FALSE(ReadMetric("payload_rmse_norm_m", j));
  EXPECT_FALSE(ReadMetric("payload_in_fov_fraction", j));
  EXPECT_FALSE(ReadMetric("retaut_quad_vz_min_mps", j));
  EXPECT_FALSE(ReadMetric("slack_detection_latency_max_s", j));
  // without a re-taut the re-taut figures are null in metrics.json, not a perfect-looking 0
  EXPECT_TRUE(j["retaut"]["quad_vz_min_mps"].is_null());
  EXPECT_TRUE(j["retaut"]["peak_body_rate_radps"].is_null());
}

TEST(MetricDefsTest, ATeamMetricIsTheWorstVehicles) {
  Metrics m;
  m.control_steps = 10;
  m.team = TeamMetrics();
  m.vehicles.resize(3);
  m.vehicles[0].tilt_max_deg = 4.0;
  m.vehicles[1].tilt_max_deg = 9.0;
  m.vehicles[2].tilt_max_deg = 2.0;
  m.vehicles[2].slack_time_s = 0.3;
  const nlohmann::json j = nlohmann::json::parse(MetricsToJson(m));
  EXPECT_EQ(ReadMetric("team_vehicle_tilt_max_deg", j), 9.0);
  EXPECT_EQ(ReadMetric("team_cable_slack_time_max_s", j), 0.3);
  // a single vehicle's run has no team: not measured
  Metrics single;
  single.control_steps = 10;
  const nlohmann::json k = nlohmann::json::parse(MetricsToJson(single));
  EXPECT_FALSE(ReadMetric("team_vehicle_tilt_max_deg", k));
  EXPECT_FALSE(ReadMetric("team_min_vehicle_separation_m", k));
}

TEST(MetricDefsTest, EveryExpectKeyBoundsADeclaredMetric) {
  std::set<std::string> paths;
  for (const MetricDef& def : MetricDefs()) paths.insert(def.json_path);
  for (const ExpectKey& k : ExpectKeys()) {
    EXPECT_EQ(paths.count(k.metric), 1u) << "expect key " << k.key << " bounds '" << k.metric
                                         << "', which metric_defs.cc does not declare";
  }
}

}  // namespace
}  // namespace hpa
