#include "hpa/scenarios/metrics.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string>

namespace hpa {
namespace {

// 150 Hz rows of a run whose payload is offset by `error` and is slack in [2, 3) s.
std::vector<LogRow> Rows(const Eigen::Vector3d& error) {
  std::vector<LogRow> rows;
  for (int k = 0; k < 600; ++k) {
    LogRow r;
    r.time_s = k / 150.0;
    r.reference.p_WL_W = Eigen::Vector3d(0, 0, 0.7);
    r.reference.p_WQ_W = Eigen::Vector3d(0, 0, 1.2);
    r.truth.p_WQ_W = r.reference.p_WQ_W;
    r.truth.p_WL_W = r.reference.p_WL_W + error;
    const bool slack = r.time_s >= 2.0 && r.time_s < 3.0;
    r.truth.mode = slack ? CableMode::kSlack : CableMode::kTaut;
    if (slack) r.truth.p_WL_W.z() += 0.3;  // lifted: must not count in the payload RMSE
    // the estimate flags slack 4 rows (26.7 ms) late
    const bool est_slack = r.time_s >= 2.0 + 4 / 150.0 - 1e-9 && r.time_s < 3.0;
    r.estimate = r.truth;
    r.estimate.mode = est_slack ? CableMode::kSlack : CableMode::kTaut;
    r.solve_time_ms = 0.1 * (k % 10);
    rows.push_back(r);
  }
  return rows;
}

// The estimate-based payload RMSE (the paper's Table I basis: no external ground truth) uses the
// estimate in place of the truth over the same samples: taut time, from payload_rmse_from_s.
TEST(MetricsTest, PayloadRmseOfTheEstimateOverTheSameSamples) {
  MetricsInputs in;
  in.rows = Rows(Eigen::Vector3d(0.01, -0.02, 0.03));
  for (LogRow& r : in.rows) {
    r.estimate.p_WL_W = r.reference.p_WL_W + Eigen::Vector3d(-0.04, 0.0, 0.05);
    if (r.time_s < 1.0) r.estimate.p_WL_W.x() += 1.0;  // before payload_rmse_from_s: not counted
    if (r.time_s >= 2.0 && r.time_s < 3.0) r.estimate.p_WL_W.z() += 1.0;  // slack: not counted
  }
  Metrics m;
  m.payload_rmse_from_s = 1.0;
  ComputeMetrics(in, &m);
  EXPECT_NEAR(m.payload_rmse_est_m.x(), 0.04, 1e-12);
  EXPECT_NEAR(m.payload_rmse_est_m.y(), 0.0, 1e-12);
  EXPECT_NEAR(m.payload_rmse_est_m.z(), 0.05, 1e-12);
  EXPECT_NEAR(m.payload_rmse_m.y(), 0.02, 1e-12);  // the truth-based figure is unchanged
  EXPECT_NE(MetricsToJson(m).find("\"payload_rmse_est_m\""), std::string::npos);
}

TEST(MetricsTest, PayloadRmseOnlyOverTautTimeWhenSlack) {
  MetricsInputs in;
  in.rows = Rows(Eigen::Vector3d(0.01, -0.02, 0.03));
  Metrics m;
  ComputeMetrics(in, &m);
  EXPECT_EQ(m.payload_rmse_over, "taut_time");
  EXPECT_NEAR(m.payload_rmse_m.x(), 0.01, 1e-12);
  EXPECT_NEAR(m.payload_rmse_m.y(), 0.02, 1e-12);
  EXPECT_NEAR(m.payload_rmse_m.z(), 0.03, 1e-12);
  EXPECT_EQ(m.slack_events, 1);
  EXPECT_NEAR(m.slack_time_s, 1.0, 1.0 / 150 + 1e-9);  // one control period of resolution
  ASSERT_TRUE(m.slack_detection_latency_max_s.has_value());
  EXPECT_NEAR(*m.slack_detection_latency_max_s, 4 / 150.0, 1e-9);
  EXPECT_NEAR(m.mode_accuracy, 1.0 - 4.0 / 600.0, 1e-12);
  EXPECT_EQ(m.retaut_count, 1);
  EXPECT_NEAR(m.mpc_solve_ms.max, 0.9, 1e-12);
}

// A single vehicle's run writes one entry of its own metrics: its slack, re-taut count,
// failures and solve times as the run's, its physics-rate extremes as the runner measured them.
TEST(MetricsTest, ASingleVehicleIsAListOfOneVehicle) {
  MetricsInputs in;
  in.rows = Rows(Eigen::Vector3d(0.01, 0, 0));
  UpdateVehicleExtremes(Eigen::Vector4d(1, 0, 0, 0), 0.98, &in.extremes);
  // a 30 deg roll and a 25 N snap, then a smaller tension: the maxima stay
  UpdateVehicleExtremes(Eigen::Vector4d(std::cos(M_PI / 12), std::sin(M_PI / 12), 0, 0), 25.0,
                        &in.extremes);
  UpdateVehicleExtremes(Eigen::Vector4d(1, 0, 0, 0), 1.1, &in.extremes);
  Metrics m;
  ComputeMetrics(in, &m);
  ASSERT_EQ(m.vehicles.size(), 1u);
  const VehicleMetrics& v = m.vehicles[0];
  EXPECT_EQ(v.slack_time_s, m.slack_time_s);
  EXPECT_EQ(v.slack_events, 1);
  EXPECT_EQ(v.retaut_count, m.retaut_count);
  EXPECT_EQ(v.control_failures, m.mpc_failures);
  EXPECT_EQ(v.solve_ms.max, m.mpc_solve_ms.max);
  EXPECT_NEAR(v.tilt_max_deg, 30.0, 1e-9);
  EXPECT_EQ(v.cable_tension_max_N, 25.0);
  const std::string json = MetricsToJson(m);
  EXPECT_NE(json.find("\"cable_tension_max_N\": 25.0"), std::string::npos) << json;
  EXPECT_EQ(json.find("\"team\""), std::string::npos);
}

// What a team run does not measure is one list: the team runner marks each field and
// metrics.json writes each path null, whatever the field held (a single vehicle's defaults, such
// as payload_in_fov_fraction's 1.0, read as measured by an expect key otherwise).
// Whether metrics.json holds null at a dotted path, in every entry of a list on the way (a
// document without the path's first key does not hold it).
bool NullAt(const nlohmann::json& j, const std::string& dotted) {
  const size_t dot = dotted.find('.');
  const std::string key = dotted.substr(0, dot);
  if (!j.is_object() || !j.contains(key)) return false;
  const nlohmann::json& at = j.at(key);
  if (dot == std::string::npos) return at.is_null();
  const std::string rest = dotted.substr(dot + 1);
  if (!at.is_array()) return NullAt(at, rest);
  for (const nlohmann::json& entry : at) {
    if (!NullAt(entry, rest)) return false;
  }
  return !at.empty();
}

TEST(MetricsTest, ATeamNullsExactlyWhatItDoesNotMeasure) {
  Metrics m;
  m.control_steps = 10;
  m.team = TeamMetrics{0.7, 1.0};
  m.vehicles.resize(2);
  m.faults.resize(1);
  m.faults[0].payload_lost = true;
  m.contacts_payload_rotor = 0;
  m.slack_detection_latency_max_s = 0.01;
  m.retaut_quad_vz_min_mps = -0.3;
  m.retaut_count = 2;
  MarkUnmeasured(TeamUnmeasuredMetrics(), &m);
  EXPECT_TRUE(std::isnan(m.payload_in_fov_fraction));
  EXPECT_TRUE(std::isnan(m.quad_rmse_m.x()));
  EXPECT_FALSE(m.retaut_quad_vz_min_mps.has_value());
  const nlohmann::json j = nlohmann::json::parse(MetricsToJson(m));
  for (const UnmeasuredMetric& u : TeamUnmeasuredMetrics()) {
    EXPECT_TRUE(NullAt(j, u.json_key)) << u.json_key;
  }
  EXPECT_EQ(j["retaut"]["count"], 2);  // the team's own re-tauts are measured
  EXPECT_EQ(j["vehicles"].size(), 2u);
  // team.vehicles: the same entries with each vehicle's update timing
  for (size_t i = 0; i < 2; ++i) {
    nlohmann::json entry = j["team"]["vehicles"][i];
    EXPECT_TRUE(entry.contains("solve_ms"));
    entry.erase("solve_ms");
    EXPECT_EQ(entry, j["vehicles"][i]);
  }
  ExpectSpec e;
  e.bounds["payload_in_fov_min"] = {0.9};
  CheckExpectations(e, &m);
  EXPECT_FALSE(m.expect_passed);
}

TEST(MetricsTest, ARunWithoutItsCameraNullsWhatTheCameraWouldMeasure) {
  Metrics m;
  m.control_steps = 10;
  m.vehicles.resize(1);
  m.camera_frames = 3;
  m.payload_in_fov_fraction = 1.0;
  m.vehicles[0].payload_in_fov_fraction = 1.0;
  m.camera_region_fraction = 0.5;
  const nlohmann::json flown = nlohmann::json::parse(MetricsToJson(m));
  m.camera_flown = false;
  MarkUnmeasured(CameraNotFlownMetrics(), &m);
  EXPECT_TRUE(std::isnan(m.payload_in_fov_fraction));
  EXPECT_FALSE(m.vehicles[0].payload_in_fov_fraction.has_value());
  EXPECT_FALSE(m.camera_region_fraction.has_value());
  const nlohmann::json j = nlohmann::json::parse(MetricsToJson(m));
  for (const UnmeasuredMetric& u : CameraNotFlownMetrics()) {
    EXPECT_FALSE(NullAt(flown, u.json_key)) << u.json_key;  // a flown camera measures it
    EXPECT_TRUE(NullAt(j, u.json_key)) << u.json_key;
  }
  // an expect key on the share in view fails: not measured is never a pass
  ExpectSpec e;
  e.bounds["payload_in_fov_min"] = {0.9};
  CheckExpectations(e, &m);
  EXPECT_FALSE(m.expect_passed);
}

TEST(MetricsTest, ExpectBoundsFailWithTheKeyNamed) {
  MetricsInputs in;
  in.rows = Rows(Eigen::Vector3d(0.1, 0, 0));
  Metrics m;
  ComputeMetrics(in, &m);
  ExpectSpec e;
  e.bounds["payload_rmse_max"] = {0.05, 0.05, 0.05};
  e.bounds["crashed"] = {0.0};
  CheckExpectations(e, &m);
  EXPECT_FALSE(m.expect_passed);
  ASSERT_EQ(m.expect_failed.size(), 1u);
  EXPECT_NE(m.expect_failed[0].find("payload_rmse_max.x"), std::string::npos);
  e.bounds["payload_rmse_max"] = {0.2, 0.2, 0.2};
  CheckExpectations(e, &m);
  EXPECT_TRUE(m.expect_passed);
}

TEST(MetricsTest, QuantileIsLinearBetweenClosestRanks) {
  // R's quantile(type = 7) / numpy's default
  EXPECT_DOUBLE_EQ(Quantile({5, 1, 3, 2, 4}, 0.5), 3.0);
  EXPECT_DOUBLE_EQ(Quantile({5, 1, 3, 2, 4}, 0.99), 4.96);
  EXPECT_DOUBLE_EQ(Quantile({1, 2, 3, 4}, 0.5), 2.5);
  EXPECT_DOUBLE_EQ(Quantile({1, 2, 3, 4}, 0.25), 1.75);
  EXPECT_DOUBLE_EQ(Quantile({1, 2, 3, 4}, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(Quantile({7}, 0.9), 7.0);
  EXPECT_TRUE(std::isnan(Quantile({}, 0.5)));
  EXPECT_TRUE(std::isnan(Quantile({1, 2}, 1.5)));
}

TEST(MetricsTest, ARunWithNoControlStepHasNullTrackingMetrics) {
  Metrics m;
  ComputeMetrics(MetricsInputs{}, &m);
  const std::string json = MetricsToJson(m);
  for (const char* key :
       {"\"payload_rmse_m\": null", "\"mode_accuracy\": null", "\"payload_in_fov_fraction\": null",
        "\"quad_position_deviation_max_m\": null"}) {
    EXPECT_NE(json.find(key), std::string::npos) << key << " in " << json;
  }
}

TEST(MetricsTest, QuantilesAndJson) {
  const Quantiles q = ComputeQuantiles({5, 1, 3, 2, 4});
  EXPECT_DOUBLE_EQ(q.median, 3);
  EXPECT_DOUBLE_EQ(q.max, 5);
  Metrics m;
  m.scenario = "s";
  const std::string json = MetricsToJson(m);
  for (const char* key :
       {"\"scenario\"", "\"crash_time_s\": null", "\"payload_rmse_m\"",
        "\"slack_detection_latency_s\"", "\"retaut\"", "\"mpc_solve_ms\"", "\"expect\""}) {
    EXPECT_NE(json.find(key), std::string::npos) << key;
  }
}

// log.csv's numbers are what a stream with setprecision(7) writes (printf's %.7g): exponents,
// rounding to 7 digits, integers, negative zero, non-finite values.
TEST(MetricsTest, LogCsvWritesNumbersAsSevenDigitGeneralFormat) {
  const double values[] = {0.0,
                           -0.0,
                           1.0 / 3.0,
                           -2.5e-7,
                           1234567.89,
                           9.9999996e12,
                           1e-5,
                           42.0,
                           std::numeric_limits<double>::infinity(),
                           std::numeric_limits<double>::quiet_NaN()};
  std::vector<LogRow> rows;
  for (double v : values) {
    LogRow r;
    r.time_s = v;
    r.cost = v;
    rows.push_back(r);
  }
  const std::string path = ::testing::TempDir() + "/log_format.csv";
  WriteLogCsv(path, rows);
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // header
  for (double v : values) {
    ASSERT_TRUE(std::getline(in, line));
    std::ostringstream expected;
    expected << std::setprecision(7) << v;
    EXPECT_EQ(line.substr(0, line.find(',')), expected.str()) << line;
  }
  std::remove(path.c_str());
}

}  // namespace
}  // namespace hpa
