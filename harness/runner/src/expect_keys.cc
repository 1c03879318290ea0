#include "hpa/scenarios/expect_keys.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "hpa/models/registry.h"
#include "hpa/scenarios/metrics.h"

namespace hpa {
namespace {

constexpr double kBig = 1e3;  // generous bound on lengths (m), speeds (m/s), times (s)

std::string Failure(const std::string& key, double value, const char* op, double bound) {
  std::ostringstream out;
  out << key << ": " << value << " " << op << " " << bound;
  return out.str();
}

// metric <= bound (metric > bound fails), per value
ExpectKey Max(std::string key, std::string metric, std::string unit, std::string description,
              double max, std::function<double(const Metrics&)> read) {
  ExpectKey k{key, metric, "metric <= bound", unit, description, 1, 0.0, max, false, {}};
  k.check = [key, read](const Metrics& m, const std::vector<double>& bound) {
    const double v = read(m);
    if (std::isnan(v)) return std::vector<std::string>{key + ": not measured in this run"};
    return v > bound[0] ? std::vector<std::string>{Failure(key, v, ">", bound[0])}
                        : std::vector<std::string>{};
  };
  return k;
}

// metric >= bound (metric < bound fails)
ExpectKey Min(std::string key, std::string metric, std::string unit, std::string description,
              double min, double max, std::function<double(const Metrics&)> read) {
  ExpectKey k{key, metric, "metric >= bound", unit, description, 1, min, max, false, {}};
  k.check = [key, read](const Metrics& m, const std::vector<double>& bound) {
    const double v = read(m);
    if (std::isnan(v)) return std::vector<std::string>{key + ": not measured in this run"};
    return v < bound[0] ? std::vector<std::string>{Failure(key, v, "<", bound[0])}
                        : std::vector<std::string>{};
  };
  return k;
}

// per-axis metric <= bound, each axis named
ExpectKey AxesMax(std::string key, std::string metric, std::string description,
                  std::function<Eigen::Vector3d(const Metrics&)> read) {
  ExpectKey k{key, metric, "metric <= bound, per axis", "m", description, 3, 0.0, kBig, false, {}};
  k.check = [key, read](const Metrics& m, const std::vector<double>& bound) {
    static const char* kAxes[3] = {"x", "y", "z"};
    std::vector<std::string> failed;
    const Eigen::Vector3d v = read(m);
    for (int i = 0; i < 3; ++i) {
      if (v(i) > bound[i]) failed.push_back(Failure(key + "." + kAxes[i], v(i), ">", bound[i]));
    }
    return failed;
  };
  return k;
}

// every fault event's recovery time <= bound; `lost` says the event needed a recovery it never
// made (fails), a time of null with `lost` false means none was needed (passes); no fault event
// fails as not measured
ExpectKey FaultRecoveryMax(
    std::string key, std::string metric, std::string description,
    std::function<std::optional<double>(const FaultRecovery&)> time,
    std::function<bool(const FaultRecovery&)> needed) {
  ExpectKey k{key, metric, "metric <= bound, every fault event", "s", description, 1, 0.0, kBig,
              false, {}};
  k.check = [key, time, needed](const Metrics& m, const std::vector<double>& bound) {
    std::vector<std::string> failed;
    if (m.faults.empty()) failed.push_back(key + ": not measured in this run (no fault event)");
    for (const FaultRecovery& r : m.faults) {
      const std::string which = key + " (events." + std::to_string(r.window.event) + ")";
      const std::optional<double> t = time(r);
      if (!t && needed(r)) failed.push_back(which + ": never");
      if (t && *t > bound[0]) failed.push_back(Failure(which, *t, ">", bound[0]));
    }
    return failed;
  };
  return k;
}

// the largest payload error in any fault event's span
double FaultTrackingErrorMax(const Metrics& m) {
  double e = NAN;
  for (const FaultRecovery& r : m.faults) {
    if (r.tracking_error_max_m && !(*r.tracking_error_max_m <= e)) e = *r.tracking_error_max_m;
  }
  return e;
}

// the largest quadrotor position estimate error in any fault event's span
double FaultEstimateErrorMax(const Metrics& m) {
  double e = NAN;
  for (const FaultRecovery& r : m.faults) {
    if (r.estimate_error_max_m && !(*r.estimate_error_max_m <= e)) e = *r.estimate_error_max_m;
  }
  return e;
}

// the largest false-detection rate of any distractor fault
double FaultFalseDetectionRate(const Metrics& m) {
  double rate = NAN;
  for (const FaultRecovery& r : m.faults) {
    if (r.false_detection_rate && !(*r.false_detection_rate <= rate)) {
      rate = *r.false_detection_rate;
    }
  }
  return rate;
}

// The crash keys: whether the run must crash, or may.
void AddCrashKeys(std::vector<ExpectKey>* t) {
  {
    ExpectKey k{"crashed",
                "crashed",
                "metric == bound",
                "true | false",
                "whether the run must crash (false: any crash fails)",
                0,
                0.0,
                1.0,
                false,
                {}};
    k.check = [](const Metrics& m, const std::vector<double>& bound) {
      const bool expected = bound[0] != 0.0;
      if (expected == m.crashed) return std::vector<std::string>{};
      return std::vector<std::string>{std::string("crashed: ") + (m.crashed ? "true" : "false") +
                                      (m.crashed ? " (" + m.crash_reason.value_or("") + ")" : "") +
                                      ", expected " + (expected ? "true" : "false")};
    };
    t->push_back(k);
  }
  {
    // read by CheckExpectations: a crash fails every scenario that neither bounds `crashed` nor
    // allows one
    ExpectKey k{"crash_allowed",
                "crashed",
                "always (a crash is then no failure)",
                "true | false",
                "true: a crash is no failure of this scenario (a diagnostic case whose other "
                "bounds are its verdict)",
                0,
                0.0,
                1.0,
                false,
                {}};
    k.check = [](const Metrics&, const std::vector<double>&) { return std::vector<std::string>{}; };
    t->push_back(k);
  }
}

// The tracking, camera, estimator, solver, re-taut and contact keys of one vehicle.
void AddTrackingKeys(std::vector<ExpectKey>* t) {
  t->push_back(AxesMax("payload_rmse_max", "payload_rmse_m", "payload tracking RMSE per axis",
                       [](const Metrics& m) { return m.payload_rmse_m; }));
  t->push_back(AxesMax("quad_rmse_max", "quad_rmse_m", "quadrotor tracking RMSE per axis",
                       [](const Metrics& m) { return m.quad_rmse_m; }));
  t->push_back(Max("quad_position_deviation_max", "quad_position_deviation_max_m", "m",
                   "largest quadrotor distance from its reference", kBig,
                   [](const Metrics& m) { return m.quad_position_deviation_max_m; }));
  t->push_back(Min("quad_position_deviation_min", "quad_position_deviation_max_m", "m",
                   "a baseline must show its failure: at least this far off", 0.0, kBig,
                   [](const Metrics& m) { return m.quad_position_deviation_max_m; }));
  t->push_back(Max("payload_in_fov_max", "payload_in_fov_fraction", "fraction",
                   "share of camera frames with the payload in view, at most", 1.0,
                   [](const Metrics& m) { return m.payload_in_fov_fraction; }));
  t->push_back(Min("payload_in_fov_min", "payload_in_fov_fraction", "fraction",
                   "share of camera frames with the payload in view, at least", 0.0, 1.0,
                   [](const Metrics& m) { return m.payload_in_fov_fraction; }));
  t->push_back(Min("mode_accuracy_min", "mode_accuracy", "fraction",
                   "share of control steps whose estimated mode is the true one", 0.0, 1.0,
                   [](const Metrics& m) { return m.mode_accuracy; }));
  {
    ExpectKey k{"slack_detection_latency_max",
                "slack_detection_latency_s.max",
                "metric <= bound",
                "s",
                "slowest slack detection; a missed slack event fails",
                1,
                0.0,
                kBig,
                false,
                {}};
    k.check = [](const Metrics& m, const std::vector<double>& bound) {
      if (m.slack_events_missed > 0) {
        return std::vector<std::string>{Failure("slack_detection_latency_max (missed slack events)",
                                                m.slack_events_missed, ">", 0)};
      }
      if (m.slack_detection_latency_max_s && *m.slack_detection_latency_max_s > bound[0]) {
        return std::vector<std::string>{Failure("slack_detection_latency_max",
                                                *m.slack_detection_latency_max_s, ">", bound[0])};
      }
      return std::vector<std::string>{};
    };
    t->push_back(k);
  }
  {
    ExpectKey k = Max("mpc_failures_max", "mpc_failures", "updates",
                      "MPC updates with a QP failure, non-finite result or fallback", 1e9,
                      [](const Metrics& m) { return static_cast<double>(m.mpc_failures); });
    k.integer = true;
    t->push_back(k);
  }
  t->push_back(Min("retaut_quad_vz_min", "retaut.quad_vz_min_mps", "m/s",
                   "lowest quadrotor z velocity within 0.5 s of a re-taut, at least", -kBig, kBig,
                   [](const Metrics& m) { return m.retaut_quad_vz_min_mps.value_or(NAN); }));
  t->push_back(Max("retaut_peak_body_rate_max", "retaut.peak_body_rate_radps", "rad/s",
                   "highest body rate within 0.5 s of a re-taut, at most", kBig,
                   [](const Metrics& m) { return m.retaut_peak_body_rate_radps.value_or(NAN); }));
  t->push_back(Min("payload_quad_min_distance_min", "payload_quad_min_distance_m", "m",
                   "smallest payload-to-vehicle surface distance, at least (< 0: overlap)", -kBig,
                   kBig, [](const Metrics& m) { return m.payload_quad_min_distance_m; }));
}

// A team run's keys (NaN, not measured, in a single-vehicle run).
void AddTeamKeys(std::vector<ExpectKey>* t) {
  const auto over_vehicles = [](const Metrics& m, double VehicleMetrics::*field) {
    if (!m.team || m.vehicles.empty()) return static_cast<double>(NAN);
    double worst = -INFINITY;
    for (const VehicleMetrics& v : m.vehicles) worst = std::max(worst, v.*field);
    return worst;
  };
  t->push_back(Min("team_separation_min", "team.min_vehicle_separation_m", "m",
                   "smallest distance between two vehicles' centres, at least", 0.0, kBig,
                   [](const Metrics& m) {
                     return m.team ? m.team->min_vehicle_separation_m : static_cast<double>(NAN);
                   }));
  t->push_back(Max("team_tilt_max", "team.vehicles.tilt_max_deg", "deg",
                   "every vehicle's largest tilt, at most", 180.0,
                   [over_vehicles](const Metrics& m) {
                     return over_vehicles(m, &VehicleMetrics::tilt_max_deg);
                   }));
  t->push_back(Max("team_payload_tilt_max", "team.payload_tilt_max_deg", "deg",
                   "the payload's largest tilt, at most", 180.0, [](const Metrics& m) {
                     return m.team ? m.team->payload_tilt_max_deg : static_cast<double>(NAN);
                   }));
  t->push_back(Max("team_slack_time_max", "team.vehicles.slack_time_s", "s",
                   "every cable's slack time, at most", kBig, [over_vehicles](const Metrics& m) {
                     return over_vehicles(m, &VehicleMetrics::slack_time_s);
                   }));
  t->push_back(Max("team_tension_max", "team.vehicles.cable_tension_max_N", "N",
                   "every cable's largest tension at the physics rate (a snap's peak), at most",
                   kBig, [over_vehicles](const Metrics& m) {
                     return over_vehicles(m, &VehicleMetrics::cable_tension_max_N);
                   }));
  t->push_back(Min("team_slack_time_min", "team.vehicles.slack_time_s", "s",
                   "the slackest cable's slack time, at least (a push that slackens a cable)", 0.0,
                   kBig, [over_vehicles](const Metrics& m) {
                     return over_vehicles(m, &VehicleMetrics::slack_time_s);
                   }));
}

// The fault keys: each fault event's recovery and effect.
void AddFaultKeys(std::vector<ExpectKey>* t) {
  t->push_back(FaultRecoveryMax(
      "fault_health_flag_max", "fault_recovery.health_flag_s",
      "the estimator's health flags every fault event within this (never: fails)",
      [](const FaultRecovery& r) { return r.health_flag_s; },
      [](const FaultRecovery&) { return true; }));
  t->push_back(FaultRecoveryMax(
      "fault_payload_back_in_view_max", "fault_recovery.payload_back_in_view_s",
      "after each fault event's end the payload is back in view within this (never lost: passes)",
      [](const FaultRecovery& r) { return r.payload_back_in_view_s; },
      [](const FaultRecovery& r) { return r.payload_lost; }));
  t->push_back(FaultRecoveryMax(
      "fault_tracking_recovered_max", "fault_recovery.tracking_recovered_s",
      "after each fault event's end the payload error is back within its tracking_bound within "
      "this (never out: passes)",
      [](const FaultRecovery& r) { return r.tracking_recovered_s; },
      [](const FaultRecovery& r) { return r.tracking_left_bound; }));
  t->push_back(Max("fault_tracking_error_max", "fault_recovery.tracking_error_max_m", "m",
                   "largest payload error in any fault event's span, at most", kBig,
                   FaultTrackingErrorMax));
  t->push_back(Min("fault_tracking_error_min", "fault_recovery.tracking_error_max_m", "m",
                   "a fault must show its effect: the largest payload error in a fault event's "
                   "span at least this",
                   0.0, kBig, FaultTrackingErrorMax));
  t->push_back(Max("fault_estimate_error_max", "fault_recovery.estimate_error_max_m", "m",
                   "largest error of the quadrotor's position estimate in any fault event's span, "
                   "at most",
                   kBig, FaultEstimateErrorMax));
  t->push_back(Min("fault_estimate_error_min", "fault_recovery.estimate_error_max_m", "m",
                   "a sensor fault must show its effect: the largest position estimate error in a "
                   "fault event's span at least this",
                   0.0, kBig, FaultEstimateErrorMax));
  t->push_back(Max("fault_false_detection_rate_max", "fault_recovery.false_detection_rate",
                   "fraction",
                   "share of a distractor fault's detections that landed on the distractor, at "
                   "most (the largest over its distractor faults)",
                   1.0, FaultFalseDetectionRate));
  t->push_back(Min("fault_false_detection_rate_min", "fault_recovery.false_detection_rate",
                   "fraction",
                   "a distractor must fool the detector: the largest share of a distractor "
                   "fault's detections on the distractor at least this",
                   0.0, 1.0, FaultFalseDetectionRate));
}

std::vector<ExpectKey> BuildTable() {
  std::vector<ExpectKey> t;
  AddCrashKeys(&t);
  AddTrackingKeys(&t);
  AddTeamKeys(&t);
  AddFaultKeys(&t);
  return t;
}

Registry<ExpectKey>& TheRegistry() {
  static Registry<ExpectKey> registry("expect key", BuildTable());
  return registry;
}

}  // namespace

const std::vector<ExpectKey>& ExpectKeys() { return TheRegistry().All(); }

const ExpectKey* FindExpectKey(const std::string& key) { return TheRegistry().Find(key); }

void RegisterExpectKey(ExpectKey key) {
  if (!key.check)
    throw std::invalid_argument("register expect key: '" + key.key + "' has no check");
  TheRegistry().Add(std::move(key));
}

}  // namespace hpa
