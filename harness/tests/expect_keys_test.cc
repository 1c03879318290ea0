// Every expect key, pass and fail, and parsed from YAML, from the one table (docs/schema.md lists
// it: ctest cli.schema_docs).

#include "hpa/scenarios/expect_keys.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

#include "hpa/models/input_error.h"
#include "hpa/scenarios/metrics.h"
#include "hpa/scenarios/scenario.h"

namespace hpa {
namespace {

// One key's case: a bound, a change of the metrics that meets it and one that breaks it.
struct Case {
  std::vector<double> bound;
  std::function<void(Metrics*)> pass, fail;
};

// A run with one fault event whose recovery `set` fills.
std::function<void(Metrics*)> OneFault(std::function<void(FaultRecovery*)> set) {
  return [set](Metrics* m) {
    m->faults = {FaultRecovery{}};
    set(&m->faults[0]);
  };
}

// A team run whose vehicles have these largest tilts and slack times.
void TeamVehicles(Metrics* m, const std::vector<double>& tilt_max_deg,
                  const std::vector<double>& slack_time_s) {
  m->team = TeamMetrics{0.6, 0.0};
  m->vehicles.clear();
  for (size_t i = 0; i < tilt_max_deg.size(); ++i) {
    VehicleMetrics v;
    v.tilt_max_deg = tilt_max_deg[i];
    v.slack_time_s = slack_time_s[i];
    m->vehicles.push_back(v);
  }
}

const std::map<std::string, Case>& Cases() {
  static const std::map<std::string, Case> cases = {
      {"crashed",
       {{0.0},
        [](Metrics* m) { m->crashed = false; },
        [](Metrics* m) {
          m->crashed = true;
          m->crash_reason = "tilt > 90 deg";
        }}},
      {"crash_allowed", {{1.0}, [](Metrics*) {}, nullptr}},
      {"team_separation_min",
       {{0.5},
        [](Metrics* m) { m->team = TeamMetrics{0.6, 0.0}; },
        [](Metrics* m) { m->team = TeamMetrics{0.4, 0.0}; }}},
      {"team_payload_tilt_max",
       {{10.0},
        [](Metrics* m) { m->team = TeamMetrics{0.6, 9.0}; },
        [](Metrics* m) { m->team = TeamMetrics{0.6, 11.0}; }}},
      {"team_tilt_max",
       {{10.0},
        [](Metrics* m) { TeamVehicles(m, {9.0, 10.0}, {0.0, 0.0}); },
        [](Metrics* m) { TeamVehicles(m, {9.0, 11.0}, {0.0, 0.0}); }}},
      {"team_slack_time_max",
       {{0.5},
        [](Metrics* m) { TeamVehicles(m, {0.0, 0.0}, {0.5, 0.1}); },
        [](Metrics* m) { TeamVehicles(m, {0.0, 0.0}, {0.1, 0.6}); }}},
      {"team_slack_time_min",
       {{0.1},
        [](Metrics* m) { TeamVehicles(m, {0.0, 0.0}, {0.0, 0.2}); },
        [](Metrics* m) { TeamVehicles(m, {0.0, 0.0}, {0.05, 0.0}); }}},
      {"team_tension_max",
       {{30.0},
        [](Metrics* m) {
          TeamVehicles(m, {0.0, 0.0}, {0.0, 0.0});
          m->vehicles[1].cable_tension_max_N = 30.0;
        },
        [](Metrics* m) {
          TeamVehicles(m, {0.0, 0.0}, {0.0, 0.0});
          m->vehicles[0].cable_tension_max_N = 31.0;
        }}},
      {"payload_rmse_max",
       {{0.1, 0.1, 0.1},
        [](Metrics* m) { m->payload_rmse_m = Eigen::Vector3d(0.09, 0, 0.1); },
        [](Metrics* m) { m->payload_rmse_m = Eigen::Vector3d(0, 0, 0.11); }}},
      {"quad_rmse_max",
       {{0.1, 0.1, 0.1},
        [](Metrics* m) { m->quad_rmse_m = Eigen::Vector3d(0.1, 0.1, 0.1); },
        [](Metrics* m) { m->quad_rmse_m = Eigen::Vector3d(0, 0.2, 0); }}},
      {"quad_position_deviation_max",
       {{0.15},
        [](Metrics* m) { m->quad_position_deviation_max_m = 0.14; },
        [](Metrics* m) { m->quad_position_deviation_max_m = 0.16; }}},
      {"quad_position_deviation_min",
       {{0.1},
        [](Metrics* m) { m->quad_position_deviation_max_m = 0.2; },
        [](Metrics* m) { m->quad_position_deviation_max_m = 0.05; }}},
      {"payload_in_fov_max",
       {{0.8},
        [](Metrics* m) { m->payload_in_fov_fraction = 0.7; },
        [](Metrics* m) { m->payload_in_fov_fraction = 0.9; }}},
      {"payload_in_fov_min",
       {{0.99},
        [](Metrics* m) { m->payload_in_fov_fraction = 1.0; },
        [](Metrics* m) { m->payload_in_fov_fraction = 0.95; }}},
      {"mode_accuracy_min",
       {{0.9},
        [](Metrics* m) { m->mode_accuracy = 0.95; },
        [](Metrics* m) { m->mode_accuracy = 0.85; }}},
      {"slack_detection_latency_max",
       {{0.1},
        [](Metrics* m) { m->slack_detection_latency_max_s = 0.06; },
        [](Metrics* m) { m->slack_events_missed = 1; }}},
      {"mpc_failures_max",
       {{0.0}, [](Metrics* m) { m->mpc_failures = 0; }, [](Metrics* m) { m->mpc_failures = 2; }}},
      {"retaut_quad_vz_min",
       {{-0.5},
        [](Metrics* m) { m->retaut_quad_vz_min_mps = -0.3; },
        [](Metrics* m) { m->retaut_quad_vz_min_mps = -0.7; }}},
      {"retaut_peak_body_rate_max",
       {{1.0},
        [](Metrics* m) { m->retaut_peak_body_rate_radps = 0.8; },
        [](Metrics* m) { m->retaut_peak_body_rate_radps = 1.2; }}},
      {"payload_quad_min_distance_min",
       {{0.0},
        [](Metrics* m) { m->payload_quad_min_distance_m = 0.01; },
        [](Metrics* m) { m->payload_quad_min_distance_m = -0.01; }}},
      {"fault_health_flag_max",
       {{0.5}, OneFault([](FaultRecovery* r) { r->health_flag_s = 0.4; }),
        OneFault([](FaultRecovery*) {})}},
      {"fault_payload_back_in_view_max",
       {{0.5}, OneFault([](FaultRecovery*) {}), OneFault([](FaultRecovery* r) {
          r->payload_lost = true;
          r->payload_back_in_view_s = 0.6;
        })}},
      {"fault_tracking_recovered_max",
       {{1.0}, OneFault([](FaultRecovery* r) {
          r->tracking_left_bound = true;
          r->tracking_recovered_s = 0.9;
        }),
        OneFault([](FaultRecovery* r) { r->tracking_left_bound = true; })}},
      {"fault_tracking_error_max",
       {{0.2}, OneFault([](FaultRecovery* r) { r->tracking_error_max_m = 0.1; }),
        OneFault([](FaultRecovery* r) { r->tracking_error_max_m = 0.3; })}},
      {"fault_tracking_error_min",
       {{0.2}, OneFault([](FaultRecovery* r) { r->tracking_error_max_m = 0.3; }),
        OneFault([](FaultRecovery* r) { r->tracking_error_max_m = 0.1; })}},
      {"fault_estimate_error_max",
       {{0.2}, OneFault([](FaultRecovery* r) { r->estimate_error_max_m = 0.1; }),
        OneFault([](FaultRecovery* r) { r->estimate_error_max_m = 0.3; })}},
      {"fault_estimate_error_min",
       {{0.2}, OneFault([](FaultRecovery* r) { r->estimate_error_max_m = 0.3; }),
        OneFault([](FaultRecovery* r) { r->estimate_error_max_m = 0.1; })}},
      {"fault_false_detection_rate_max",
       {{0.2}, OneFault([](FaultRecovery* r) { r->false_detection_rate = 0.1; }),
        OneFault([](FaultRecovery* r) { r->false_detection_rate = 0.3; })}},
      {"fault_false_detection_rate_min",
       {{0.2}, OneFault([](FaultRecovery* r) { r->false_detection_rate = 0.3; }),
        OneFault([](FaultRecovery* r) { r->false_detection_rate = 0.1; })}},
  };
  return cases;
}

TEST(ExpectKeysTest, EveryKeyPassesAndFailsOnItsMetric) {
  for (const ExpectKey& k : ExpectKeys()) {
    // keys that other tests of this binary register describe themselves as "(test)"
    if (k.description.find("(test)") != std::string::npos) continue;
    const auto c = Cases().find(k.key);
    ASSERT_NE(c, Cases().end()) << "expect key '" << k.key << "' has no test case here";
    if (!c->second.fail) continue;  // a key that never fails by itself (crash_allowed: below)
    ExpectSpec spec;
    spec.bounds[k.key] = c->second.bound;
    Metrics passing, failing;
    c->second.pass(&passing);
    c->second.fail(&failing);
    CheckExpectations(spec, &passing);
    CheckExpectations(spec, &failing);
    EXPECT_TRUE(passing.expect_passed) << k.key;
    ASSERT_FALSE(failing.expect_passed) << k.key;
    EXPECT_EQ(failing.expect_failed[0].rfind(k.key, 0), 0u) << failing.expect_failed[0];
  }
  EXPECT_EQ(Cases().size(), ExpectKeys().size()) << "a case for a key that is not in the table";
}

TEST(ExpectKeysTest, ACrashFailsAScenarioThatDoesNotExpectOne) {
  // summaries and expect_failure_rate read expect.passed: a crash the scenario does not bound
  // must be a failure there too, not only in the exit code
  Metrics crashed;
  crashed.crashed = true;
  crashed.crash_reason = "rotor_strike";
  ExpectSpec silent;
  silent.bounds["quad_position_deviation_max"] = {1.0};
  CheckExpectations(silent, &crashed);
  ASSERT_FALSE(crashed.expect_passed);
  EXPECT_EQ(crashed.expect_failed[0].rfind("crashed: true (rotor_strike)", 0), 0u)
      << crashed.expect_failed[0];
  // a scenario that says a crash may happen decides by its own bound
  ExpectSpec allowed;
  allowed.bounds["crashed"] = {1.0};
  CheckExpectations(allowed, &crashed);
  EXPECT_TRUE(crashed.expect_passed);
  // crash_allowed: the crash is no failure, the other bounds still are
  ExpectSpec diagnostic;
  diagnostic.bounds["crash_allowed"] = {1.0};
  diagnostic.bounds["mpc_failures_max"] = {0.0};
  CheckExpectations(diagnostic, &crashed);
  EXPECT_TRUE(crashed.expect_passed);
  crashed.mpc_failures = 2;
  CheckExpectations(diagnostic, &crashed);
  EXPECT_FALSE(crashed.expect_passed);
  diagnostic.bounds["crash_allowed"] = {0.0};
  crashed.mpc_failures = 0;
  CheckExpectations(diagnostic, &crashed);
  EXPECT_FALSE(crashed.expect_passed);
}

// A scenario whose expect block is `expect: {KEY: VALUE}`.
// (a team's key in a team scenario: a bound on what the kind of run does not measure is refused)
std::string ScenarioWithExpect(const std::string& key, const std::string& value) {
  const bool team = key.rfind("team_", 0) == 0;
  const std::string kind =
      team ? "world: {profile: ideal}\npayload: {mass_kg: 0.2}\n"
             "vehicles:\n  - {attach_m: [0.35, 0, 0]}\n  - {attach_m: [-0.35, 0, 0]}\n"
           : "controller: {type: geometric}\nestimation: {ground_truth: true}\n";
  return "name: expect_case\nduration: 1.0\n" + kind +
         "reference: {type: hover, payload_position: [0, 0, 0.7]}\n"
         "expect: {" +
         key + ": " + value + "}\n";
}

// A bound of a key's size, every value `v` (a boolean key: true / false).
std::string BoundText(const ExpectKey& k, double v) {
  if (k.size == 0) return v != 0.0 ? "true" : "false";
  std::ostringstream text;
  text.precision(17);
  if (k.size == 1) {
    text << v;
  } else {
    text << "[";
    for (int i = 0; i < k.size; ++i) text << (i ? ", " : "") << v;
    text << "]";
  }
  return text.str();
}

TEST(ExpectKeysTest, EveryKeyParsesFromYamlWithinItsRange) {
  for (const ExpectKey& k : ExpectKeys()) {
    EXPECT_FALSE(k.description.empty()) << k.key;
    EXPECT_FALSE(k.unit.empty()) << k.key;
    // in range: the loader stores the bound as written
    const double inside = k.size == 0 ? 1.0 : (k.integer ? std::floor(k.max) : k.max);
    const Scenario s = LoadScenarioText(ScenarioWithExpect(k.key, BoundText(k, inside)), "case");
    ASSERT_TRUE(s.expect.Has(k.key)) << k.key;
    EXPECT_EQ(s.expect.bounds.at(k.key), std::vector<double>(std::max(1, k.size), inside)) << k.key;
    if (k.size == 0) continue;
    // beyond its range, or of the wrong size: refused, naming the key
    const std::vector<std::string> refused = {BoundText(k, k.max + 1.0 + std::fabs(k.max)),
                                              BoundText(k, k.min - 1.0 - std::fabs(k.min)),
                                              k.size == 1 ? "[1, 2]" : "0.5", "\"tight\""};
    for (const std::string& value : refused) {
      try {
        LoadScenarioText(ScenarioWithExpect(k.key, value), "case");
        ADD_FAILURE() << k.key << ": " << value << " was accepted";
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(k.key), std::string::npos)
            << k.key << ": " << value << ": " << e.what();
      }
    }
  }
  EXPECT_THROW(LoadScenarioText(ScenarioWithExpect("payload_rmse_maximum", "0.1"), "case"),
               InputError);
}

}  // namespace
}  // namespace hpa
