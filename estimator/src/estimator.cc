// The estimator's interface (CableEstimator, cable_estimator.h): the sensor messages in, each
// ending with the health check, the estimate and the health counters out, the payload where the
// variant and the mode put it; and the factories of the hybrid and the always-taut estimators.

#include "hpa/estimator/estimator.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "cable_estimator.h"
#include "hpa/estimator/vehicle_filter.h"

namespace hpa {

CableEstimator::CableEstimator(bool hybrid, TautPayload taut_payload, const EstimatorConfig& config,
                               const Params& params, const SystemState& initial)
    : hybrid_(hybrid),
      taut_payload_(taut_payload),
      config_(config),
      params_(params),
      quad_(params, config.quad_filter, QuadFilterStateFrom(initial)),
      cable_(params, config.cable_ekf, InitialXi(initial, params.cable_length_m),
             InitialXiDot(initial, params.cable_length_m), initial.time_s),
      mode_detector_(params, config.mode_detector, InitialMode(hybrid, params, initial),
                     (initial.p_WL_W - initial.p_WQ_W).norm()),
      tracker_(params, config.payload_tracker),
      tension_cue_(params, config.tension_cue,
                   InitialMode(hybrid, params, initial) == CableMode::kSlack),
      support_(params, config.support_detector),
      thrust_N_(params.HoverThrustN()),
      mode_(InitialMode(hybrid, params, initial)),
      initial_time_s_(initial.time_s) {
  Matrix6d tracker_cov = Matrix6d::Zero();
  tracker_cov.diagonal() << Eigen::Vector3d::Constant(config.initial_payload_position_var_m2),
      Eigen::Vector3d::Constant(config.initial_payload_velocity_var_m2ps2);
  tracker_.Reset(initial.time_s, initial.p_WL_W, initial.v_WL_W, tracker_cov);
}

void CableEstimator::OnImu(const ImuSample& imu) {
  if (quad_.Predict(imu) != FilterStatus::kOk) return;
  TrackImu(imu);
  CheckHealth();
}

void CableEstimator::OnVio(const VioSample& vio) {
  quad_.UpdateVio(vio);
  if (VioUsable(vio)) last_vio_ = vio;
  CheckHealth();
}

void CableEstimator::OnAllocatedThrust(double thrust_N) {
  if (std::isfinite(thrust_N)) {
    thrust_N_ = thrust_N;
  } else {
    ++thrust_commands_non_finite_;
  }
}

void CableEstimator::OnPayloadDetection(const PayloadDetection& detection) {
  TakeDetection(detection);
  CheckHealth();
}

SystemState CableEstimator::Estimate(double time_s) const {
  const QuadFilterState& quad = quad_.state();
  SystemState out;
  out.time_s = time_s;
  // short extrapolation if the caller asks slightly ahead of the last IMU sample
  const double ahead_s = std::clamp(time_s - quad.time_s, 0.0, config_.max_extrapolation_s);
  out.p_WQ_W = quad.p_WB_W + quad.v_WB_W * ahead_s;
  out.v_WQ_W = quad.v_WB_W;
  out.q_WB = quad.q_WB;
  out.w_B = quad.w_B_radps;
  out.mode = hybrid_ ? mode_ : CableMode::kTaut;
  out.payload_visible = payload_visible_;
  out.payload_lost = UnseenFor(time_s) > config_.payload_lost_after_s;
  out.payload_lost =
      PayloadAt(time_s, out.p_WQ_W, out.v_WQ_W, &out.p_WL_W, &out.v_WL_W) || out.payload_lost;
  out.payload_supported = out.mode == CableMode::kSlack && support_.supported();
  if (!out.p_WL_W.allFinite() || !out.v_WL_W.allFinite()) {
    // unreachable after CheckHealth; the controller still never sees a non-finite payload
    out.p_WL_W = out.p_WQ_W - Eigen::Vector3d(0, 0, params_.cable_length_m);
    out.v_WL_W = out.v_WQ_W;
    out.payload_lost = true;
  }
  return out;
}

EstimatorHealth CableEstimator::Health() const {
  EstimatorHealth health;
  health.quad_filter = quad_.counts();
  health.cable_ekf = cable_.counts();
  health.payload_tracker = tracker_.counts();
  health.detections_lost = detections_lost_;
  health.detections_non_finite = detections_non_finite_;
  health.thrust_commands_non_finite = thrust_commands_non_finite_;
  health.slack_entries = slack_entries_;
  health.slack_entries_by_tension = slack_entries_by_tension_;
  health.retaut_restarts = retaut_restarts_;
  health.retaut_restarts_by_tension = retaut_restarts_by_tension_;
  health.cable_reinitialisations = cable_reinitialisations_;
  health.health_resets = health_resets_;
  health.slack = hybrid_ && mode_ == CableMode::kSlack;
  health.filtered_cable_length_m = mode_detector_.filtered_length_m();
  return health;
}

// Forced accepts and rejections of the payload tracker, forced accepts of the quadrotor
// filter and health resets, summed: a change means a detection was an outlier, or the frame
// the detections are located in jumped.
int CableEstimator::FrameJumps() const {
  return quad_.counts().forced_accepts + tracker_.counts().forced_accepts +
         tracker_.counts().rejected_updates + health_resets_.Total();
}

// Seconds since the newest detection taken (since the start before the first).
double CableEstimator::UnseenFor(double time_s) const {
  return time_s - (seen_ ? last_seen_time_s_ : initial_time_s_);
}

// The cable filter's covariance at a restart: the re-taut standard deviations per component.
CableMatrix CableEstimator::RetautCovariance() const {
  CableMatrix cov = CableMatrix::Zero();
  cov.diagonal() << Eigen::Vector3d::Constant(std::pow(config_.retaut_xi_std, 2)),
      Eigen::Vector3d::Constant(std::pow(config_.retaut_xi_dot_std_per_s, 2));
  return cov;
}

// The payload at time_s for a quadrotor at p_WQ_W, v_WQ_W, by the variant and the mode; true
// when the slack prediction has run into the vehicle (the payload is then lost).
bool CableEstimator::PayloadAt(double time_s, const Eigen::Vector3d& p_WQ_W,
                               const Eigen::Vector3d& v_WQ_W, Eigen::Vector3d* p_WL_W,
                               Eigen::Vector3d* v_WL_W) const {
  const double measured_age_s = time_s - measured_time_s_;
  if (!hybrid_ && taut_payload_ == TautPayload::kMeasured && has_measured_ &&
      measured_age_s <= config_.measured_payload_max_age_s) {
    // as measured (a payload lifted along the cable is an error the controller sees),
    // carried from the capture time to now at the measured velocity
    *p_WL_W = measured_p_WL_W_ + measured_v_WL_W_ * std::max(0.0, measured_age_s);
    *v_WL_W = measured_v_WL_W_;
    return false;
  }
  if (!hybrid_ || mode_ == CableMode::kTaut) {
    *p_WL_W = p_WQ_W + params_.cable_length_m * cable_.xi_W();
    *v_WL_W = v_WQ_W + params_.cable_length_m * cable_.xi_dot_W();
    return false;
  }
  tracker_.PredictTo(time_s, p_WL_W, v_WL_W);
  Eigen::Vector3d p_fit_WL_W, v_fit_WL_W;
  if (support_.supported() && payload_visible_ && support_.fit_start_s() > held_fit_after_s_ &&
      support_.MotionAt(time_s, &p_fit_WL_W, &v_fit_WL_W)) {
    // held and in view: across the image where the fit of its detections puts it (a hand is
    // not in free fall); the tracker keeps its height
    p_WL_W->head<2>() = p_fit_WL_W.head<2>();
    v_WL_W->head<2>() = v_fit_WL_W.head<2>();
  } else if (support_.supported() && !payload_visible_) {
    // held up and out of view: carried on from where it was last seen at its last horizontal
    // velocity (a hand does not let it fall, nor stop where the camera lost it)
    Eigen::Vector3d v_held_WL_W = tracker_.state().tail<3>();
    v_held_WL_W.z() = 0.0;
    const double unseen_s = std::max(0.0, time_s - tracker_.time_s());
    *p_WL_W = tracker_.state().head<3>() + v_held_WL_W * unseen_s;
    *v_WL_W = v_held_WL_W;
  }
  // the cable cannot stretch: between the true re-taut and its detection, free fall would
  // carry the payload past the sphere |x_L - x_Q| = l; hold it on the sphere instead
  const Eigen::Vector3d d = *p_WL_W - p_WQ_W;
  if (d.norm() > params_.cable_length_m) {
    const Eigen::Vector3d xi = d.normalized();
    *p_WL_W = p_WQ_W + params_.cable_length_m * xi;
    const double outward_mps = (*v_WL_W - v_WQ_W).dot(xi);
    if (outward_mps > 0) *v_WL_W -= outward_mps * xi;
  }
  return tracker_hit_vehicle_;
}

Eigen::Vector3d CableEstimator::InitialXi(const SystemState& s, double l_m) {
  const Eigen::Vector3d d = s.p_WL_W - s.p_WQ_W;
  return d.norm() > 1e-6 ? Eigen::Vector3d(d.normalized()) : Eigen::Vector3d(0, 0, -1);
}

Eigen::Vector3d CableEstimator::InitialXiDot(const SystemState& s, double l_m) {
  const Eigen::Vector3d xi = InitialXi(s, l_m);
  const Eigen::Vector3d rel = (s.v_WL_W - s.v_WQ_W) / l_m;
  return rel - xi.dot(rel) * xi;
}

CableMode CableEstimator::InitialMode(bool hybrid, const Params& p, const SystemState& s) {
  if (!hybrid) return CableMode::kTaut;
  return (s.p_WL_W - s.p_WQ_W).norm() < p.cable_length_m - p.slack_epsilon_m ? CableMode::kSlack
                                                                             : CableMode::kTaut;
}

std::unique_ptr<Estimator> MakeHybridEstimator(const EstimatorConfig& config, const Params& params,
                                               const SystemState& initial) {
  return std::make_unique<CableEstimator>(true, TautPayload::kProjected, config, params, initial);
}

std::unique_ptr<Estimator> MakeAlwaysTautEstimator(const EstimatorConfig& config,
                                                   const Params& params,
                                                   const SystemState& initial) {
  return std::make_unique<CableEstimator>(false, TautPayload::kMeasured, config, params, initial);
}

std::unique_ptr<Estimator> MakeAlwaysTautProjectedEstimator(const EstimatorConfig& config,
                                                            const Params& params,
                                                            const SystemState& initial) {
  return std::make_unique<CableEstimator>(false, TautPayload::kProjected, config, params, initial);
}

}  // namespace hpa
