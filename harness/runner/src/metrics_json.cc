#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "hpa/scenarios/metrics.h"
#include "hpa/scenarios/provenance.h"

namespace hpa {
namespace {

using Json = nlohmann::ordered_json;

// Writes null at a dotted metrics.json path ("retaut.quad_vz_min_mps"), into every entry of a
// list on the way ("vehicles.camera_frames"); a path the document does not hold is left alone.
void NullAtPath(const std::string& dotted, Json* o) {
  const size_t dot = dotted.find('.');
  const std::string key = dotted.substr(0, dot);
  if (!o->is_object() || !o->contains(key)) return;
  Json& at = (*o)[key];
  if (dot == std::string::npos) {
    at = Json();
    return;
  }
  const std::string rest = dotted.substr(dot + 1);
  if (at.is_array()) {
    for (Json& entry : at) NullAtPath(rest, &entry);
  } else {
    NullAtPath(rest, &at);
  }
}

// JSON of a number: null when not finite
Json Num(double v) { return std::isfinite(v) ? Json(v) : Json(); }
// JSON of an optional number: null when unset or not finite
Json OptNum(const std::optional<double>& v) { return v ? Num(*v) : Json(); }
// JSON of an optional count: null when unset
Json OptInt(const std::optional<int>& v) { return v ? Json(*v) : Json(); }
// JSON of an optional string: null when unset
Json OptStr(const std::optional<std::string>& v) { return v ? Json(*v) : Json(); }
// JSON of a vector as [x, y, z]
Json Vec(const Eigen::Vector3d& v) { return Json::array({Num(v.x()), Num(v.y()), Num(v.z())}); }
// JSON of a timing's median, p99 and max
Json QuantilesJson(const Quantiles& q) {
  return Json{{"median", Num(q.median)}, {"p99", Num(q.p99)}, {"max", Num(q.max)}};
}

// The estimator's variant, then its health counts (integers as integers) and filter states.
Json EstimatorJson(const Metrics& m) {
  Json estimator = {{"variant", m.estimator}};
  for (const auto& [name, value] : m.estimator_health) {
    estimator[name] = std::isfinite(value) && value == std::floor(value) && std::fabs(value) < 1e15
                          ? Json(static_cast<long long>(value))
                          : Num(value);
  }
  return estimator;
}

// The causes of a fault's estimator resets as the estimator's health names them
// (health_resets_<cause>), each its count; null when not measured.
Json HealthResetsJson(const std::optional<EstimatorHealthResets>& resets) {
  if (!resets) return Json();
  EstimatorHealth health;
  health.health_resets = *resets;
  const std::string prefix = "health_resets_";
  Json by_cause = Json::object();
  for (const auto& [name, value] : health.Fields()) {
    if (name.rfind(prefix, 0) == 0) by_cause[name.substr(prefix.size())] = static_cast<int>(value);
  }
  return by_cause;
}

// One fault event's entry of metrics.json's `faults`.
Json FaultJson(const FaultRecovery& r) {
  const FaultWindow& w = r.window;
  return {{"event", w.event},
          {"vehicle", w.vehicle},
          {"component", w.component},
          {"mode", w.mode},
          {"start_s", Num(w.start_s)},
          {"end_s", OptNum(w.end_s)},
          {"span_end_s", Num(r.span_end_s)},
          {"health_flag_s", OptNum(r.health_flag_s)},
          {"payload_lost", r.payload_lost},
          {"payload_back_in_view_s", OptNum(r.payload_back_in_view_s)},
          {"tracking_bound_m", Num(w.tracking_bound_m)},
          {"tracking_left_bound", r.tracking_left_bound},
          {"tracking_recovered_s", OptNum(r.tracking_recovered_s)},
          {"tracking_error_max_m", OptNum(r.tracking_error_max_m)},
          {"estimate_error_max_m", OptNum(r.estimate_error_max_m)},
          {"estimator_resets", OptInt(r.estimator_resets)},
          {"rejected_updates", OptInt(r.rejected_updates)},
          {"health_resets", HealthResetsJson(r.health_resets)},
          {"distractor_drawn_fraction", OptNum(r.distractor_drawn_fraction)},
          {"distractor_in_image_fraction", OptNum(r.distractor_in_image_fraction)},
          {"detections", OptInt(r.detections)},
          {"false_detections", OptInt(r.false_detections)},
          {"false_detection_rate", OptNum(r.false_detection_rate)}};
}

// metrics.json's `faults` (one entry per fault event) and `fault_recovery` (the slowest recovery
// over them; null: none applies).
void AddFaults(const Metrics& m, Json* o) {
  Json faults = Json::array();
  std::optional<double> worst_flag_s, worst_view_s, worst_tracking_s, worst_error_m,
      worst_estimate_m, worst_false_rate;
  int unrecovered = 0;
  const auto worst = [](std::optional<double>* w, const std::optional<double>& v) {
    if (v && (!*w || *v > **w)) *w = v;
  };
  for (const FaultRecovery& r : m.faults) {
    faults.push_back(FaultJson(r));
    worst(&worst_flag_s, r.health_flag_s);
    worst(&worst_view_s, r.payload_back_in_view_s);
    worst(&worst_tracking_s, r.tracking_recovered_s);
    worst(&worst_error_m, r.tracking_error_max_m);
    worst(&worst_estimate_m, r.estimate_error_max_m);
    worst(&worst_false_rate, r.false_detection_rate);
    const bool lost_for_good = r.payload_lost && !r.payload_back_in_view_s;
    const bool out_for_good = r.tracking_left_bound && !r.tracking_recovered_s;
    unrecovered += (lost_for_good || out_for_good) ? 1 : 0;
  }
  (*o)["faults"] = faults;
  (*o)["fault_recovery"] = {{"health_flag_s", OptNum(worst_flag_s)},
                            {"payload_back_in_view_s", OptNum(worst_view_s)},
                            {"tracking_recovered_s", OptNum(worst_tracking_s)},
                            {"tracking_error_max_m", OptNum(worst_error_m)},
                            {"estimate_error_max_m", OptNum(worst_estimate_m)},
                            {"false_detection_rate", OptNum(worst_false_rate)},
                            {"unrecovered", unrecovered}};
}

// A team run measured none of the single vehicle's quadrotor, estimator, camera or contact
// metrics that its vehicles do not measure: null, never a perfect-looking value (the re-taut's
// count is the team's).
void NullTeamUnmeasured(const Metrics& m, Json* o) {
  for (const UnmeasuredMetric& u : TeamUnmeasuredMetrics()) {
    if ((m.team->onboard && u.onboard_measures) || (m.team->cameras && u.camera_measures)) {
      continue;
    }
    NullAtPath(u.json_key, o);
  }
}

// Every vehicle's own metrics (one for a single vehicle) under `vehicles`, and for a team
// `team` with the machine's timing of each vehicle's updates under team.vehicles, so that
// `vehicles` is the run's alone.
void AddVehicles(const Metrics& m, bool controlled, Json* o) {
  const auto measured = [&](const Json& v) { return controlled ? v : Json(); };
  Json vehicles = Json::array(), team_vehicles = Json::array();
  for (const VehicleMetrics& v : m.vehicles) {
    Json entry = {{"slack_time_s", measured(Num(v.slack_time_s))},
                  {"slack_events", v.slack_events},
                  {"retaut_count", v.retaut_count},
                  {"tilt_max_deg", measured(Num(v.tilt_max_deg))},
                  {"cable_tension_max_N", measured(Num(v.cable_tension_max_N))},
                  {"mixer_saturated_fraction", measured(Num(v.mixer_saturated_fraction))},
                  {"control_failures", v.control_failures},
                  {"camera_frames", v.camera_frames},
                  {"payload_in_fov_fraction", OptNum(v.payload_in_fov_fraction)}};
    vehicles.push_back(entry);
    entry["solve_ms"] = QuantilesJson(v.solve_ms);
    team_vehicles.push_back(entry);
  }
  (*o)["vehicles"] = vehicles;
  if (m.team) {
    (*o)["team"] = {{"vehicle_count", m.vehicles.size()},
                    {"min_vehicle_separation_m", measured(Num(m.team->min_vehicle_separation_m))},
                    {"payload_tilt_max_deg", measured(Num(m.team->payload_tilt_max_deg))},
                    {"vehicle_state", m.team->onboard ? "onboard" : "motion_capture"},
                    {"vehicles", team_vehicles}};
  }
}

// A run whose rendered camera was not flown (a separate stack that uses no pixels): the camera's
// counts and timings are null, not a perfect-looking zero.
void NullCameraNotFlown(const Metrics& m, Json* o) {
  if (m.camera_flown) return;
  for (const UnmeasuredMetric& u : CameraNotFlownMetrics()) NullAtPath(u.json_key, o);
}

// The run's identity, its end, and the tracking, slack and camera metrics.
Json RunJson(const Metrics& m, bool controlled) {
  // a run that ended before its first control step (or camera frame) measured nothing: null,
  // not a perfect-looking zero
  const auto measured = [&](const Json& v) { return controlled ? v : Json(); };
  Json o;
  o["scenario"] = m.scenario;
  o["controller"] = m.controller;
  o["camera"] = m.camera;
  o["seed"] = m.seed;
  o["build"] = BuildToJson(ThisBuild());
  o["sim_time_s"] = Num(m.sim_time_s);
  o["wall_time_s"] = Num(m.wall_time_s);
  o["crashed"] = m.crashed;
  o["crash_time_s"] = OptNum(m.crash_time_s);
  o["crash_reason"] = OptStr(m.crash_reason);
  o["run_error"] = OptStr(m.run_error);
  o["payload_rmse_m"] = measured(Vec(m.payload_rmse_m));
  o["payload_rmse_est_m"] = measured(Vec(m.payload_rmse_est_m));
  o["payload_rmse_over"] = m.payload_rmse_over;
  o["payload_rmse_from_s"] = Num(m.payload_rmse_from_s);
  o["quad_rmse_m"] = measured(Vec(m.quad_rmse_m));
  o["quad_position_deviation_max_m"] = measured(Num(m.quad_position_deviation_max_m));
  o["payload_max_speed_mps"] = measured(Num(m.payload_max_speed_mps));
  o["slack_time_s"] = Num(m.slack_time_s);
  o["slack_events"] = m.slack_events;
  o["mode_accuracy"] = measured(Num(m.mode_accuracy));
  o["slack_detection_latency_s"] = {{"mean", OptNum(m.slack_detection_latency_mean_s)},
                                    {"max", OptNum(m.slack_detection_latency_max_s)},
                                    {"missed", m.slack_events_missed}};
  o["payload_in_fov_fraction"] = m.camera_frames > 0 ? Num(m.payload_in_fov_fraction) : Json();
  o["payload_lost_time_s"] = measured(Num(m.payload_lost_time_s));
  o["mixer_saturated_fraction"] = measured(Num(m.mixer_saturated_fraction));
  o["camera_frames"] = m.camera_frames;
  o["detections"] = m.detections;
  return o;
}

}  // namespace

std::string MetricsToJson(const Metrics& m) {
  const bool controlled = m.control_steps > 0;
  Json o = RunJson(m, controlled);
  o["retaut"] = {{"count", m.retaut_count},
                 {"quad_vz_min_mps", OptNum(m.retaut_quad_vz_min_mps)},
                 {"peak_body_rate_radps", OptNum(m.retaut_peak_body_rate_radps)}};
  o["mpc_solve_ms"] = QuantilesJson(m.mpc_solve_ms);
  o["mpc_failures"] = m.mpc_failures;
  o["closed_loop_cost"] = Num(m.closed_loop_cost);
  o["world_profile"] = m.world_profile;
  o["flight_stack"] = m.flight_stack;
  o["payload_quad_min_distance_m"] = Num(m.payload_quad_min_distance_m);
  o["contacts"] = {{"payload_body", m.contacts_payload_body},
                   {"payload_rotor", m.contacts_payload_rotor},
                   {"payload_ground", m.contacts_payload_ground},
                   {"quad_ground", m.contacts_quad_ground},
                   {"payload_gripper", m.contacts_payload_gripper}};
  o["render_ms"] = QuantilesJson(m.render_ms);
  o["image_model_ms"] = QuantilesJson(m.image_model_ms);
  o["detector_ms"] = QuantilesJson(m.detector_ms);
  o["camera_region_fraction"] = OptNum(m.camera_region_fraction);
  if (!m.estimator.empty()) o["estimator"] = EstimatorJson(m);
  if (!m.faults.empty()) AddFaults(m, &o);
  if (m.team) NullTeamUnmeasured(m, &o);
  AddVehicles(m, controlled, &o);
  NullCameraNotFlown(m, &o);
  o["expect"] = {{"passed", m.expect_passed}, {"failed", m.expect_failed}};
  return o.dump(2) + "\n";
}
}  // namespace hpa
