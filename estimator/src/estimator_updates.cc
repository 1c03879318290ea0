// The estimator's updates on each camera frame (CableEstimator, cable_estimator.h): the detection
// located in the body and world frames, the mode decision, then the filter the mode says: the
// slack entry and the free-fall tracker's updates, the cable EKF's restart at re-taut with its
// velocity row, the taut updates with the restart of a diverged filter, and the always-taut
// variants' measured payload.

#include <algorithm>
#include <cmath>

#include "cable_estimator.h"

namespace hpa {

// One camera frame's result: the mode decision, then the filter the mode says.
void CableEstimator::TakeDetection(const PayloadDetection& detection) {
  payload_visible_ = detection.found;
  if (!detection.found) {
    ++detections_lost_;
    return;
  }
  if (!detection.p_CL_C.allFinite() || !std::isfinite(detection.time_s)) {
    ++detections_non_finite_;
    payload_visible_ = false;
    return;
  }
  seen_ = true;
  last_seen_time_s_ = detection.time_s;
  tracker_hit_vehicle_ = false;
  const LocatedDetection d = Locate(detection);

  // always-taut variants: the EKF takes the raw measurement whatever its length
  if (!hybrid_) {
    cable_.Update(d.time_s, d.p_BL_B, d.R_WB, d.cov_B);
    if (taut_payload_ == TautPayload::kMeasured) UpdateMeasuredPayload(d.time_s, d.p_WL_W);
    return;
  }

  // a slack entry flagged by the tension cue restarts the tracker from this first detection
  // as a geometric entry would (its velocity from the last two detections)
  const bool entered_by_tension = tension_entry_pending_;
  tension_entry_pending_ = false;
  const CableMode previous = entered_by_tension ? CableMode::kTaut : mode_;
  const CableMode geometric = mode_detector_.Update(d.time_s, d.p_BL_B.norm());
  // slack if either cue says so: a payload held at the cable's length is slack to the
  // tension cue, a payload thrown up faster than the low pass follows to the geometry
  const bool tension_slack = config_.tension_cue.enabled && tension_cue_.slack();
  mode_ = geometric == CableMode::kSlack || tension_slack ? CableMode::kSlack : CableMode::kTaut;
  const PreviousDetection last{has_last_detection_, last_p_WL_W_, last_p_BL_B_,
                               last_detection_time_s_};
  has_last_detection_ = true;
  last_p_WL_W_ = d.p_WL_W;
  last_p_BL_B_ = d.p_BL_B;
  last_detection_time_s_ = d.time_s;
  const Eigen::Matrix3d cov_W =
      d.R_WB * d.cov_B * d.R_WB.transpose() + quad_.covariance().block<3, 3>(0, 0);
  if (mode_ == CableMode::kSlack) {
    if (previous == CableMode::kTaut) {
      EnterSlack(d, last, cov_W, entered_by_tension);
      if (!entered_by_tension) {
        support_.Clear();
        slack_entered_at_s_ = d.time_s;
      }
    } else {
      tracker_.Update(d.time_s, d.p_WL_W, cov_W);
    }
    // an outlier, or a jump of the vehicle's estimate (a forced VIO update, a restart) that
    // moves every later detection: the fit of a held payload's motion starts again after it
    const int frame_jumps = FrameJumps();
    if (frame_jumps != frame_jumps_) held_fit_after_s_ = d.time_s;
    frame_jumps_ = frame_jumps;
    // only frames captured since the cable unloaded (a push's frames before it are not free)
    if (d.time_s >= slack_entered_at_s_) support_.Add(d.time_s, d.p_WL_W);
    return;
  }
  // the cable EKF was frozen while slack, also while a tension-cue slack waited for its
  // first detection: back to taut it restarts from this detection
  if (previous == CableMode::kSlack || entered_by_tension) {
    RestartCableAtRetaut(d);
    return;
  }
  if (velocity_row_pending_) FuseRetautVelocity(d, last);
  UpdateTautCable(d);
}

// The detection in body and world frames with the body-frame covariance of its position
// (detection noise model plus floor), at the quadrotor pose of its capture time.
CableEstimator::LocatedDetection CableEstimator::Locate(const PayloadDetection& detection) const {
  LocatedDetection d;
  d.time_s = detection.time_s;
  d.p_BL_B = params_.t_BC_B_m + params_.R_BC * detection.p_CL_C;
  d.cov_B = params_.R_BC *
                DetectionCovariance_C(params_, config_.detection_noise, detection.p_CL_C) *
                params_.R_BC.transpose() +
            Eigen::Matrix3d::Identity() * std::pow(config_.detection_noise_floor_m, 2);
  d.quad_then = quad_.StateAt(detection.time_s).value_or(quad_.state());
  d.R_WB = d.quad_then.q_WB.toRotationMatrix();
  d.p_WL_W = d.quad_then.p_WB_W + d.R_WB * d.p_BL_B;
  return d;
}

// Enters slack at a detection: starts the free-fall tracker there, its velocity from the last
// two detections (free fall between them) when recent, else from the taut model.
void CableEstimator::EnterSlack(const LocatedDetection& d, const PreviousDetection& last,
                                const Eigen::Matrix3d& cov_W, bool entered_by_tension) {
  Matrix6d cov = Matrix6d::Zero();
  cov.block<3, 3>(0, 0) = cov_W;
  Eigen::Vector3d v_WL_W = d.quad_then.v_WB_W + params_.cable_length_m * cable_.xi_dot_W();
  double velocity_std_mps = config_.slack_entry_velocity_std_mps;
  const double gap_s = d.time_s - last.time_s;
  if (last.valid && gap_s > config_.slack_entry_min_detection_gap_s &&
      gap_s < config_.slack_entry_max_detection_gap_s) {
    v_WL_W = (d.p_WL_W - last.p_WL_W) / gap_s -
             Eigen::Vector3d(0, 0, 0.5 * params_.gravity_mps2 * gap_s);
    velocity_std_mps = std::sqrt(2.0 * cov_W.trace() / 3.0) / gap_s;
  }
  cov.block<3, 3>(3, 3).diagonal().setConstant(std::pow(velocity_std_mps, 2));
  tracker_.Reset(d.time_s, d.p_WL_W, v_WL_W, cov);
  if (!entered_by_tension) ++slack_entries_;
}

// Re-taut: restarts the cable EKF on the measured direction and the tracker's velocity (radial
// part removed, as in the inelastic collision of docs/design.md section 4).
void CableEstimator::RestartCableAtRetaut(const LocatedDetection& d) {
  Eigen::Vector3d p_L, v_L;
  tracker_.PredictTo(quad_.state().time_s, &p_L, &v_L);
  const Eigen::Vector3d xi = (d.R_WB * d.p_BL_B).normalized();
  const Eigen::Vector3d xi_dot = (v_L - quad_.state().v_WB_W) / params_.cable_length_m;
  const CableMatrix cov = RetautCovariance();
  cable_.Reset(quad_.state().time_s, xi, xi_dot, cov);
  ++retaut_restarts_;
  velocity_row_pending_ = config_.retaut_velocity_row;
  restart_time_s_ = quad_.state().time_s;
}

// The first detection after a re-taut restart fuses the rate of the body-frame payload position
// between the restart's detection and this one, at the middle of their gap; the restart is at
// the time the restart's detection arrived, later than its capture, so no earlier than that.
void CableEstimator::FuseRetautVelocity(const LocatedDetection& d, const PreviousDetection& last) {
  velocity_row_pending_ = false;
  const double gap_s = d.time_s - last.time_s;
  const double fuse_time_s = std::max(d.time_s - 0.5 * gap_s, restart_time_s_);
  if (last.valid && gap_s > config_.slack_entry_min_detection_gap_s &&
      gap_s < config_.slack_entry_max_detection_gap_s) {
    const QuadFilterState quad_mid = quad_.StateAt(fuse_time_s).value_or(d.quad_then);
    cable_.UpdateVelocity(fuse_time_s, (d.p_BL_B - last.p_BL_B) / gap_s,
                          quad_mid.q_WB.toRotationMatrix(), quad_mid.w_B_radps,
                          2.0 * d.cov_B / (gap_s * gap_s));
  }
}

// A taut detection to the cable EKF. A run of rejected detections that agree with each other
// means the filter has diverged (e.g. on a thrust it was wrongly told), not the camera: it
// restarts from the detections rather than lock them out or fuse one into a filter that is
// sure of the wrong state.
void CableEstimator::UpdateTautCable(const LocatedDetection& d) {
  const Eigen::Vector3d xi_detected_W = (d.R_WB * d.p_BL_B).normalized();
  if (cable_.consecutive_rejections() >= cable_.config().gate.max_consecutive_rejections &&
      RejectedRunAgrees(xi_detected_W)) {
    const double gap_s = d.time_s - rejected_times_s_.back();
    const Eigen::Vector3d xi_dot_W =
        gap_s > 0.0 ? Eigen::Vector3d((xi_detected_W - rejected_xi_W_.back()) / gap_s)
                    : Eigen::Vector3d::Zero();
    const CableMatrix cov = RetautCovariance();
    cable_.Reset(quad_.state().time_s, xi_detected_W, xi_dot_W, cov);
    rejected_xi_W_.clear();
    rejected_times_s_.clear();
    ++cable_reinitialisations_;
    return;
  }
  if (cable_.Update(d.time_s, d.p_BL_B, d.R_WB, d.cov_B) == FilterStatus::kRejected) {
    rejected_xi_W_.push_back(xi_detected_W);
    rejected_times_s_.push_back(d.time_s);
    if (rejected_xi_W_.size() > 3) {
      rejected_xi_W_.pop_front();
      rejected_times_s_.pop_front();
    }
  } else {
    rejected_xi_W_.clear();
    rejected_times_s_.clear();
  }
}

// Whether the rejected run and `xi_W` agree with each other: a smooth swing (successive
// directions within kAgreeRad, about a 10 rad/s swing between 30 Hz frames), not outliers.
bool CableEstimator::RejectedRunAgrees(const Eigen::Vector3d& xi_W) const {
  constexpr double kAgreeRad = 0.35;
  if (rejected_xi_W_.empty()) return false;
  Eigen::Vector3d previous = rejected_xi_W_.front();
  for (size_t i = 1; i <= rejected_xi_W_.size(); ++i) {
    const Eigen::Vector3d& next = i < rejected_xi_W_.size() ? rejected_xi_W_[i] : xi_W;
    if (std::acos(std::clamp(previous.dot(next), -1.0, 1.0)) > kAgreeRad) return false;
    previous = next;
  }
  return true;
}

// The measured payload: the newest detection in world and a low-passed finite difference of
// consecutive detections (a first-order filter with time constant tau, alpha = dt/(tau + dt)).
void CableEstimator::UpdateMeasuredPayload(double time_s, const Eigen::Vector3d& p_WL_W) {
  const double gap_s = time_s - measured_time_s_;
  if (has_measured_ && gap_s > 0.0 && gap_s <= config_.measured_velocity_max_gap_s) {
    const Eigen::Vector3d v_raw_WL_W = (p_WL_W - measured_p_WL_W_) / gap_s;
    const double alpha = gap_s / (config_.measured_velocity_time_constant_s + gap_s);
    measured_v_WL_W_ += alpha * (v_raw_WL_W - measured_v_WL_W_);
  }
  if (!has_measured_ || gap_s > 0.0) {
    measured_p_WL_W_ = p_WL_W;
    measured_time_s_ = time_s;
    has_measured_ = true;
  }
}

}  // namespace hpa
