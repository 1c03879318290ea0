#include "hpa/scenarios/metric_defs.h"

#include <stdexcept>
#include <vector>

#include "hpa/models/registry.h"

namespace hpa {
namespace {

constexpr double kControlPeriodS = 1.0 / 150.0;  // one control step: the finest latency step

// Each declaration: name, json path, read, unit, better, min effect, timing, compared, label,
// description.

// A run's crash, tracking, camera, estimator, slack, re-taut, contact, solver and expect metrics.
std::vector<MetricDef> RunMetricDefs() {
  using R = MetricRead;
  return {
      {"crashed", "crashed", R::kFlag, "0/1", Better::kLower, 0.05, false, false, "crashed",
       "the run ended in a crash (1) or not (0)"},
      {"payload_rmse_norm_m", "payload_rmse_m", R::kNorm, "m", Better::kLower, 0.005, false, true,
       "payload RMSE norm [m]",
       "payload tracking RMSE against the reference, norm of the axes (taut time only when "
       "the run had slack)"},
      {"payload_rmse_est_norm_m", "payload_rmse_est_m", R::kNorm, "m", Better::kLower, 0.005, false,
       false, "payload RMSE norm, estimate [m]",
       "the same with the onboard estimate in place of the truth (the paper's basis)"},
      {"quad_rmse_norm_m", "quad_rmse_m", R::kNorm, "m", Better::kLower, 0.005, false, false, "",
       "quadrotor tracking RMSE against its flat reference, norm of the axes"},
      {"quad_position_deviation_max_m", "quad_position_deviation_max_m", R::kNumber, "m",
       Better::kLower, 0.01, false, true, "quad deviation max [m]",
       "largest quadrotor distance from its reference over the run"},
      {"payload_in_fov_fraction", "payload_in_fov_fraction", R::kNumber, "fraction",
       Better::kHigher, 0.01, false, true, "payload in view",
       "share of camera frames with the payload centre in view"},
      {"payload_lost_time_s", "payload_lost_time_s", R::kNumber, "s", Better::kLower, 0.05, false,
       false, "payload lost [s]", "time the estimator reported the payload lost"},
      {"mode_accuracy", "mode_accuracy", R::kNumber, "fraction", Better::kHigher, 0.01, false, true,
       "mode accuracy", "share of control steps whose estimated mode is the true one"},
      {"slack_time_s", "slack_time_s", R::kNumber, "s", Better::kNeither, 0.05, false, false, "",
       "time the cable was truly slack"},
      {"slack_detection_latency_max_s", "slack_detection_latency_s.max", R::kNumber, "s",
       Better::kLower, kControlPeriodS, false, true, "slack detection latency max [s]",
       "slowest detection of a true slack event"},
      {"retaut_quad_vz_min_mps", "retaut.quad_vz_min_mps", R::kIfRetauted, "m/s", Better::kHigher,
       0.05, false, true, "re-taut v_z min [m/s]",
       "lowest quadrotor z velocity within 0.5 s of a re-taut (runs with a re-taut)"},
      {"retaut_peak_body_rate_radps", "retaut.peak_body_rate_radps", R::kIfRetauted, "rad/s",
       Better::kLower, 0.2, false, true, "re-taut peak body rate [rad/s]",
       "highest body rate within 0.5 s of a re-taut (runs with a re-taut)"},
      {"payload_quad_min_distance_m", "payload_quad_min_distance_m", R::kNumber, "m",
       Better::kHigher, 0.005, false, false, "",
       "smallest payload-to-vehicle surface distance (negative: they overlapped)"},
      {"mixer_saturated_fraction", "mixer_saturated_fraction", R::kNumber, "fraction",
       Better::kLower, 0.01, false, false, "",
       "share of rate-loop allocations that fell short of the demand"},
      {"mpc_failures", "mpc_failures", R::kNumber, "updates", Better::kLower, 1.0, false, false,
       "MPC failures", "MPC updates with a QP failure, non-finite result or fallback"},
      {"expect_passed", "expect.passed", R::kFlag, "0/1", Better::kHigher, 0.05, false, false,
       "expect passed", "the scenario's expect bounds held (1) or not (0)"},
  };
}

// Each fault event's recovery and effect, the worst over the run's fault events.
std::vector<MetricDef> FaultMetricDefs() {
  using R = MetricRead;
  return {
      {"fault_health_flag_s", "fault_recovery.health_flag_s", R::kNumber, "s", Better::kLower,
       kControlPeriodS, false, false, "",
       "slowest time from a fault event's start until the estimator's health flagged it "
       "(runs with a fault event; null: none flagged)"},
      {"fault_payload_back_in_view_s", "fault_recovery.payload_back_in_view_s", R::kNumber, "s",
       Better::kLower, 0.05, false, false, "",
       "slowest time from a fault event's end until the payload was back in view (null: "
       "never lost, or never back)"},
      {"fault_tracking_recovered_s", "fault_recovery.tracking_recovered_s", R::kNumber, "s",
       Better::kLower, 0.05, false, false, "",
       "slowest time from a fault event's end until the payload error was back within its "
       "tracking_bound (null: never out, or never back)"},
      {"fault_tracking_error_max_m", "fault_recovery.tracking_error_max_m", R::kNumber, "m",
       Better::kLower, 0.01, false, false, "",
       "largest payload error in any fault event's span (runs with a fault event)"},
      {"fault_estimate_error_max_m", "fault_recovery.estimate_error_max_m", R::kNumber, "m",
       Better::kLower, 0.01, false, false, "",
       "largest quadrotor position estimate error in any fault event's span (null with "
       "ground truth)"},
      {"fault_false_detection_rate", "fault_recovery.false_detection_rate", R::kNumber, "fraction",
       Better::kLower, 0.01, false, false, "",
       "largest share of a distractor fault's detections (made at capture in its window) "
       "that landed on the distractor rather than the payload (null: no distractor fault, "
       "or no detection)"},
      {"fault_unrecovered", "fault_recovery.unrecovered", R::kNumber, "events", Better::kLower, 1.0,
       false, false, "",
       "fault events after which the payload stayed lost or out of its tracking bound"},
  };
}

// Each vehicle's physics-rate extremes, a team's metrics, and the machine's timing.
std::vector<MetricDef> VehicleMetricDefs() {
  using R = MetricRead;
  return {
      {"cable_tension_max_N", "vehicles.cable_tension_max_N", R::kLargest, "N", Better::kLower, 1.0,
       false, false, "",
       "largest cable tension at the physics rate (a snap's peak), the worst vehicle's "
       "(minimum effect: about one payload weight)"},
      {"vehicle_tilt_max_deg", "vehicles.tilt_max_deg", R::kLargest, "deg", Better::kLower, 1.0,
       false, false, "", "largest vehicle tilt at the physics rate, the worst vehicle's"},
      {"team_min_vehicle_separation_m", "team.min_vehicle_separation_m", R::kNumber, "m",
       Better::kHigher, 0.05, false, false, "vehicle separation min [m]",
       "a team's smallest distance between two vehicles' centres (team runs)"},
      {"team_vehicle_tilt_max_deg", "team.vehicles.tilt_max_deg", R::kLargest, "deg",
       Better::kLower, 1.0, false, false, "vehicle tilt max [deg]",
       "a team's largest vehicle tilt, the worst vehicle's (team runs)"},
      {"team_payload_tilt_max_deg", "team.payload_tilt_max_deg", R::kNumber, "deg", Better::kLower,
       1.0, false, false, "payload tilt max [deg]", "a team's largest payload tilt (team runs)"},
      {"team_cable_slack_time_max_s", "team.vehicles.slack_time_s", R::kLargest, "s",
       Better::kNeither, 0.05, false, false, "cable slack max [s]",
       "a team's slackest cable's slack time (team runs)"},
      {"team_cable_tension_max_N", "team.vehicles.cable_tension_max_N", R::kLargest, "N",
       Better::kLower, 1.0, false, false, "cable tension max [N]",
       "a team's largest cable tension at the physics rate (a snap's peak), the worst "
       "cable's (team runs; minimum effect: about one payload weight)"},
      {"mpc_solve_median_ms", "mpc_solve_ms.median", R::kNumber, "ms", Better::kLower, 0.02, true,
       true, "", "median wall time of one MPC update (the machine's, not the run's)"},
  };
}

// Every metric, in the order of the tables that list them.
std::vector<MetricDef> AllMetricDefs() {
  std::vector<MetricDef> defs = RunMetricDefs();
  for (std::vector<MetricDef> (*part)() : {FaultMetricDefs, VehicleMetricDefs}) {
    std::vector<MetricDef> more = part();
    defs.insert(defs.end(), more.begin(), more.end());
  }
  return defs;
}

const Registry<MetricDef>& TheRegistry() {
  static const Registry<MetricDef> registry("metric", AllMetricDefs());
  return registry;
}

}  // namespace

const std::vector<MetricDef>& MetricDefs() { return TheRegistry().All(); }

const MetricDef* FindMetric(const std::string& name) { return TheRegistry().Find(name); }

const MetricDef& GetMetric(const std::string& name) {
  const MetricDef* def = FindMetric(name);
  if (def == nullptr) throw std::logic_error("metric '" + name + "' is not in metric_defs.cc");
  return *def;
}

}  // namespace hpa
