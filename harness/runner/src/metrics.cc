#include "hpa/scenarios/metrics.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "hpa/models/cooperative_model.h"
#include "hpa/models/input_error.h"
#include "hpa/scenarios/expect_keys.h"

namespace hpa {
namespace {

constexpr double kMinSlackInterval_s = 0.03;  // shorter true-mode flips are tendon chatter
constexpr double kRetautWindow_s = 0.5;       // window after a re-taut for vz and body rates
constexpr double kDetectionWindow_s = 0.5;    // a slack onset not flagged within this is missed

}  // namespace

double Quantile(std::vector<double> values, double q) {
  if (values.empty() || !(q >= 0.0 && q <= 1.0)) return std::nan("");
  std::sort(values.begin(), values.end());
  // linear between the closest ranks (Hyndman and Fan type 7, numpy's default)
  const double rank = q * (values.size() - 1);
  const size_t below = static_cast<size_t>(std::floor(rank));
  const size_t above = std::min(values.size() - 1, below + 1);
  return values[below] + (rank - below) * (values[above] - values[below]);
}

Quantiles ComputeQuantiles(std::vector<double> values) {
  Quantiles q;
  if (values.empty()) return q;
  q.median = Quantile(values, 0.5);
  q.p99 = Quantile(values, 0.99);
  q.max = Quantile(values, 1.0);
  return q;
}

double TiltDeg(const Eigen::Vector4d& q_wxyz) {
  const Eigen::Quaterniond q(q_wxyz(0), q_wxyz(1), q_wxyz(2), q_wxyz(3));
  const double cos_tilt = std::clamp(q.normalized().toRotationMatrix()(2, 2), -1.0, 1.0);
  return std::acos(cos_tilt) * 180.0 / M_PI;
}

std::vector<std::pair<double, double>> SlackIntervals(const std::vector<double>& times_s,
                                                      const std::vector<CableMode>& modes) {
  std::vector<std::pair<double, double>> intervals;
  for (size_t i = 0; i < modes.size();) {
    if (modes[i] != CableMode::kSlack) {
      ++i;
      continue;
    }
    size_t j = i;
    while (j < modes.size() && modes[j] == CableMode::kSlack) ++j;
    const double end = j < modes.size() ? times_s[j] : times_s.back();
    if (end - times_s[i] >= kMinSlackInterval_s) intervals.emplace_back(times_s[i], end);
    i = j;
  }
  return intervals;
}

std::vector<std::pair<double, double>> TrueSlackIntervals(const std::vector<LogRow>& rows) {
  std::vector<double> times_s;
  std::vector<CableMode> modes;
  times_s.reserve(rows.size());
  modes.reserve(rows.size());
  for (const LogRow& r : rows) {
    times_s.push_back(r.time_s);
    modes.push_back(r.truth.mode);
  }
  return SlackIntervals(times_s, modes);
}


const std::vector<UnmeasuredMetric>& TeamUnmeasuredMetrics() {
  static const std::vector<UnmeasuredMetric> list = {
      {"payload_rmse_est_m", [](Metrics* m) { m->payload_rmse_est_m.setConstant(NAN); }},
      {"quad_rmse_m", [](Metrics* m) { m->quad_rmse_m.setConstant(NAN); }},
      {"quad_position_deviation_max_m", [](Metrics* m) { m->quad_position_deviation_max_m = NAN; }},
      {"mode_accuracy", [](Metrics* m) { m->mode_accuracy = NAN; }},
      {"payload_in_fov_fraction", [](Metrics* m) { m->payload_in_fov_fraction = NAN; }, false,
       true},
      {"payload_lost_time_s", [](Metrics* m) { m->payload_lost_time_s = NAN; }},
      {"closed_loop_cost", [](Metrics* m) { m->closed_loop_cost = NAN; }},
      {"payload_quad_min_distance_m", [](Metrics* m) { m->payload_quad_min_distance_m = NAN; }},
      {"contacts", nullptr},
      {"slack_detection_latency_s",
       [](Metrics* m) {
         m->slack_detection_latency_mean_s.reset();
         m->slack_detection_latency_max_s.reset();
       }},
      {"retaut.quad_vz_min_mps", [](Metrics* m) { m->retaut_quad_vz_min_mps.reset(); }},
      // a fault's recovery as the camera and the estimator see it (its payload error is measured)
      {"fault_recovery.health_flag_s", nullptr, true},
      {"fault_recovery.payload_back_in_view_s", nullptr},
      {"fault_recovery.estimate_error_max_m", nullptr, true},
      {"fault_recovery.false_detection_rate", nullptr},
      {"retaut.peak_body_rate_radps", [](Metrics* m) { m->retaut_peak_body_rate_radps.reset(); }},
      // what a fault's payload camera would lose
      {"faults.payload_lost", nullptr},
  };
  return list;
}

const std::vector<UnmeasuredMetric>& CameraNotFlownMetrics() {
  static const std::vector<UnmeasuredMetric> list = {
      {"camera_frames", nullptr},
      {"detections", nullptr},
      {"payload_in_fov_fraction", [](Metrics* m) { m->payload_in_fov_fraction = NAN; }},
      {"render_ms", nullptr},
      {"image_model_ms", nullptr},
      {"detector_ms", nullptr},
      {"camera_region_fraction", [](Metrics* m) { m->camera_region_fraction.reset(); }},
      {"vehicles.camera_frames", nullptr},
      {"vehicles.payload_in_fov_fraction",
       [](Metrics* m) {
         for (VehicleMetrics& v : m->vehicles) v.payload_in_fov_fraction.reset();
       }},
  };
  return list;
}

bool TeamMeasures(const std::string& json_path, bool onboard, bool cameras) {
  for (const UnmeasuredMetric& u : TeamUnmeasuredMetrics()) {
    if ((onboard && u.onboard_measures) || (cameras && u.camera_measures)) continue;
    const std::string unmeasured = u.json_key;
    if (json_path == unmeasured || json_path.rfind(unmeasured + ".", 0) == 0) return false;
  }
  return true;
}

void MarkUnmeasured(const std::vector<UnmeasuredMetric>& unmeasured, Metrics* m) {
  for (const UnmeasuredMetric& u : unmeasured) {
    if (u.mark != nullptr) u.mark(m);
  }
}

void UpdateVehicleExtremes(const Eigen::Vector4d& q_WB_wxyz, double cable_tension_N,
                           VehicleMetrics* vehicle) {
  vehicle->tilt_max_deg = std::max(vehicle->tilt_max_deg, TiltDeg(q_WB_wxyz));
  vehicle->cable_tension_max_N = std::max(vehicle->cable_tension_max_N, cable_tension_N);
}

bool InPayloadRmse(double time_s, const std::vector<std::pair<double, double>>& slack,
                   double from_s) {
  if (time_s < from_s - 1e-9) return false;
  for (const auto& [start_s, end_s] : slack) {
    if (time_s >= start_s && time_s < end_s) return false;
  }
  return true;
}

const char* PayloadRmseOver(const std::vector<std::pair<double, double>>& slack) {
  return slack.empty() ? "whole_run" : "taut_time";
}

namespace {

// Tracking errors (RMS over the run; the payload's over the taut time when the cable went slack),
// speeds, mode agreement, the closed-loop cost and the time the payload was reported lost.
void TrackingMetrics(const std::vector<LogRow>& rows,
                     const std::vector<std::pair<double, double>>& slack, Metrics* m) {
  Eigen::Vector3d payload_sq = Eigen::Vector3d::Zero(), quad_sq = Eigen::Vector3d::Zero();
  Eigen::Vector3d payload_est_sq = Eigen::Vector3d::Zero();
  int payload_n = 0, mode_agree = 0;
  m->payload_rmse_over = PayloadRmseOver(slack);
  for (const LogRow& r : rows) {
    const Eigen::Vector3d e_Q = r.truth.p_WQ_W - r.reference.p_WQ_W;
    quad_sq += e_Q.cwiseAbs2();
    m->quad_position_deviation_max_m = std::max(m->quad_position_deviation_max_m, e_Q.norm());
    if (InPayloadRmse(r.time_s, slack, m->payload_rmse_from_s)) {
      payload_sq += (r.truth.p_WL_W - r.reference.p_WL_W).cwiseAbs2();
      payload_est_sq += (r.estimate.p_WL_W - r.reference.p_WL_W).cwiseAbs2();
      ++payload_n;
    }
    m->payload_max_speed_mps = std::max(m->payload_max_speed_mps, r.truth.v_WL_W.norm());
    if (r.truth.mode == r.estimate.mode) ++mode_agree;
    m->closed_loop_cost += r.cost;
  }
  m->payload_lost_time_s = 0.0;
  for (size_t i = 1; i < rows.size(); ++i) {
    if (rows[i].estimate.payload_lost)
      m->payload_lost_time_s += rows[i].time_s - rows[i - 1].time_s;
  }
  if (!rows.empty()) {
    m->quad_rmse_m = (quad_sq / rows.size()).cwiseSqrt();
    m->mode_accuracy = static_cast<double>(mode_agree) / rows.size();
  }
  if (payload_n > 0) {
    m->payload_rmse_m = (payload_sq / payload_n).cwiseSqrt();
    m->payload_rmse_est_m = (payload_est_sq / payload_n).cwiseSqrt();
  }
}

// Slack time, how late the estimator flagged each slack onset (or missed it), and the re-taut
// impact: the quadrotor's lowest vertical speed and peak body rate just after each re-taut.
void SlackMetrics(const std::vector<LogRow>& rows,
                  const std::vector<std::pair<double, double>>& slack, Metrics* m) {
  m->slack_time_s = 0.0;
  std::vector<double> latencies;
  double vz_min = std::numeric_limits<double>::infinity(), rate_peak = 0.0;
  for (const auto& [start, end] : slack) {
    m->slack_time_s += end - start;
    bool detected = false;
    for (const LogRow& r : rows) {
      if (r.time_s >= start && r.time_s <= start + kDetectionWindow_s &&
          r.estimate.mode == CableMode::kSlack) {
        latencies.push_back(r.time_s - start);
        detected = true;
        break;
      }
    }
    if (!detected) ++m->slack_events_missed;
    if (end < rows.back().time_s) {
      ++m->retaut_count;
      for (const LogRow& r : rows) {
        if (r.time_s >= end - 0.05 && r.time_s <= end + kRetautWindow_s) {
          vz_min = std::min(vz_min, r.truth.v_WQ_W.z());
          rate_peak = std::max(rate_peak, r.truth.w_B.norm());
        }
      }
    }
  }
  m->retaut_quad_vz_min_mps.reset();
  m->retaut_peak_body_rate_radps.reset();
  if (m->retaut_count > 0) {
    m->retaut_quad_vz_min_mps = vz_min;
    m->retaut_peak_body_rate_radps = rate_peak;
  }
  if (!latencies.empty()) {
    double sum = 0.0;
    for (double l : latencies) sum += l;
    m->slack_detection_latency_mean_s = sum / latencies.size();
    m->slack_detection_latency_max_s = *std::max_element(latencies.begin(), latencies.end());
  }
}

// The camera's field of view and the timing statistics: solver, detector, renderer, image model;
// MPC failures are the plans neither flown nor a designed recovery.
void CameraAndTimingMetrics(const MetricsInputs& in, Metrics* m) {
  m->camera_frames = static_cast<int>(in.payload_in_fov_per_frame.size());
  m->detections = in.detections;
  if (m->camera_frames > 0) {
    const auto visible =
        std::count(in.payload_in_fov_per_frame.begin(), in.payload_in_fov_per_frame.end(), true);
    m->payload_in_fov_fraction = static_cast<double>(visible) / m->camera_frames;
  }
  std::vector<double> solve_ms;
  m->mpc_failures = 0;
  for (const LogRow& r : in.rows) {
    solve_ms.push_back(r.solve_time_ms);
    // a plan stopped at its iteration cap is flown, a tumble recovery is by design: only real
    // failures count
    if (r.status != ControlStatus::kSuccess && r.status != ControlStatus::kMaxIterations &&
        r.status != ControlStatus::kRecovery) {
      ++m->mpc_failures;
    }
  }
  m->mpc_solve_ms = ComputeQuantiles(solve_ms);
  m->detector_ms = ComputeQuantiles(in.detector_ms);
  if (!in.render_ms.empty()) {
    m->camera_region_fraction = static_cast<double>(in.region_frames) / in.render_ms.size();
  }
  m->render_ms = ComputeQuantiles(in.render_ms);
  m->image_model_ms = ComputeQuantiles(in.image_model_ms);
}

// Each fault event's recovery over its span (its start to the start of the next fault that starts
// after it has ended, or the end of the log).

}  // namespace

std::vector<FaultRecovery> FaultRecoveries(const std::vector<LogRow>& rows,
                                           const std::vector<FaultWindow>& windows,
                                           bool ground_truth) {
  std::vector<FaultRecovery> recoveries;
  for (size_t k = 0; k < windows.size(); ++k) {
    FaultRecovery r;
    r.window = windows[k];
    const FaultWindow& w = r.window;
    double span_end_s = rows.empty() ? w.start_s : rows.back().time_s + 1e-9;
    for (const FaultWindow& later : windows) {
      const bool after_its_end = w.end_s && later.start_s >= *w.end_s - 1e-9;
      if (later.start_s > w.start_s + 1e-9 && after_its_end) {
        span_end_s = std::min(span_end_s, later.start_s);
      }
    }
    r.span_end_s = span_end_s;
    // the rows of the span, and the estimate's counts just before it
    size_t first = 0;
    while (first < rows.size() && rows[first].time_s < w.start_s - 1e-9) ++first;
    size_t last = first;  // one past the span's last row
    while (last < rows.size() && rows[last].time_s < span_end_s) ++last;
    if (first == last) {
      recoveries.push_back(r);
      continue;
    }
    const LogRow& before = rows[first > 0 ? first - 1 : first];
    const bool lost_before = first > 0 && before.estimate.payload_lost;
    const int rejected0 = first > 0 ? before.estimator_rejected_updates : 0;
    const int resets0 = first > 0 ? before.estimator_resets : 0;
    const double recovery_from_s = w.end_s.value_or(w.start_s);
    std::optional<size_t> last_lost, last_out;
    double error_max_m = 0.0, estimate_error_max_m = 0.0;
    for (size_t i = first; i < last; ++i) {
      const LogRow& row = rows[i];
      const bool flagged = row.estimator_rejected_updates > rejected0 ||
                           row.estimator_resets > resets0 ||
                           (row.estimate.payload_lost && !lost_before);
      if (flagged && !r.health_flag_s) r.health_flag_s = row.time_s - w.start_s;
      if (row.estimate.payload_lost) last_lost = i;
      const double error_m = (row.truth.p_WL_W - row.reference.p_WL_W).norm();
      error_max_m = std::max(error_max_m, error_m);
      estimate_error_max_m =
          std::max(estimate_error_max_m, (row.estimate.p_WQ_W - row.truth.p_WQ_W).norm());
      if (error_m > w.tracking_bound_m) last_out = i;
    }
    r.tracking_error_max_m = error_max_m;
    if (!ground_truth) r.estimate_error_max_m = estimate_error_max_m;
    // back: the row after the last one out, if the span goes on past it
    const auto back_after = [&](const std::optional<size_t>& last_bad) -> std::optional<double> {
      if (!last_bad || *last_bad + 1 >= last) return std::nullopt;
      return std::max(0.0, rows[*last_bad + 1].time_s - recovery_from_s);
    };
    r.payload_lost = last_lost.has_value();
    r.payload_back_in_view_s = back_after(last_lost);
    r.tracking_left_bound = last_out.has_value();
    r.tracking_recovered_s = back_after(last_out);
    r.estimator_resets = rows[last - 1].estimator_resets - resets0;
    r.rejected_updates = rows[last - 1].estimator_rejected_updates - rejected0;
    // the health check's resets by cause in the span: the counts at its end less those before it
    const std::optional<EstimatorHealthResets>& end = rows[last - 1].estimator_health_resets;
    const std::optional<EstimatorHealthResets> start =
        first > 0 ? before.estimator_health_resets : EstimatorHealthResets{};
    if (end && start) {
      EstimatorHealthResets d;
      d.quad_non_finite = end->quad_non_finite - start->quad_non_finite;
      d.payload_non_finite = end->payload_non_finite - start->payload_non_finite;
      d.payload_speed = end->payload_speed - start->payload_speed;
      d.cable_length = end->cable_length - start->cable_length;
      r.health_resets = d;
    }
    recoveries.push_back(r);
  }
  return recoveries;
}

void ComputeMetrics(const MetricsInputs& in, Metrics* m) {
  const auto& rows = in.rows;
  m->control_steps = static_cast<int>(rows.size());
  const auto slack = TrueSlackIntervals(rows);
  m->slack_events = static_cast<int>(slack.size());
  TrackingMetrics(rows, slack, m);
  m->mixer_saturated_fraction =
      in.rate_loop_steps > 0 ? static_cast<double>(in.mixer_saturated_steps) / in.rate_loop_steps
                             : 0.0;
  SlackMetrics(rows, slack, m);
  CameraAndTimingMetrics(in, m);
  m->faults = FaultRecoveries(in.rows, in.faults, in.ground_truth);
  // the one vehicle's own metrics, as a team's vehicles have theirs
  VehicleMetrics vehicle = in.extremes;
  vehicle.slack_time_s = m->slack_time_s;
  vehicle.slack_events = m->slack_events;
  vehicle.retaut_count = m->retaut_count;
  vehicle.mixer_saturated_fraction = m->mixer_saturated_fraction;
  vehicle.control_failures = m->mpc_failures;
  vehicle.solve_ms = m->mpc_solve_ms;
  vehicle.camera_frames = m->camera_frames;
  if (m->camera_frames > 0) vehicle.payload_in_fov_fraction = m->payload_in_fov_fraction;
  m->vehicles = {vehicle};
}

bool AddFaultFrameTallies(const std::vector<sim::FaultFrameTally>& tallies, Metrics* m) {
  bool added = false;
  std::vector<bool> taken(m->faults.size(), false);
  for (const sim::FaultFrameTally& t : tallies) {
    if (!t.distractor) continue;
    for (size_t k = 0; k < m->faults.size(); ++k) {
      FaultRecovery& r = m->faults[k];
      if (taken[k] || r.window.mode != "distractor" ||
          std::fabs(r.window.start_s - t.start_s) > 1e-9) {
        continue;
      }
      taken[k] = true;
      added = true;
      if (t.frames > 0) {
        r.distractor_drawn_fraction = static_cast<double>(t.drawn_frames) / t.frames;
        r.distractor_in_image_fraction = static_cast<double>(t.in_image_frames) / t.frames;
      }
      r.detections = t.detections;
      r.false_detections = t.detections_on_distractor;
      if (t.detections > 0) {
        r.false_detection_rate = static_cast<double>(t.detections_on_distractor) / t.detections;
      }
      break;
    }
  }
  return added;
}

void CheckExpectations(const ExpectSpec& e, Metrics* m) {
  m->expect_failed.clear();
  if (m->run_error) m->expect_failed.push_back("run aborted: " + *m->run_error);
  // a crash fails every scenario that neither bounds `crashed` itself nor allows a crash
  const auto allowed = e.bounds.find("crash_allowed");
  const bool crash_allowed = allowed != e.bounds.end() && allowed->second.at(0) != 0.0;
  if (m->crashed && !e.Has("crashed") && !crash_allowed) {
    m->expect_failed.push_back("crashed: true (" + m->crash_reason.value_or("") +
                               "), and the scenario does not expect a crash");
  }
  for (const ExpectKey& k : ExpectKeys()) {
    const auto bound = e.bounds.find(k.key);
    if (bound == e.bounds.end()) continue;
    for (std::string& failure : k.check(*m, bound->second)) {
      m->expect_failed.push_back(std::move(failure));
    }
  }
  m->expect_passed = m->expect_failed.empty();
}

}  // namespace hpa
