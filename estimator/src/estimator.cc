#include "hpa/estimator/estimator.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <optional>

namespace hpa {
namespace {

// Where an always-taut estimator puts the payload.
enum class TautPayload {
  kMeasured,   // the detections' position and low-passed finite-difference velocity
  kProjected,  // on the cable sphere: x_Q + l xi from the cable EKF
};

// Quadrotor filter + cable EKF, and when hybrid the mode detector and the free-fall payload
// tracker; not hybrid, the mode is always taut and the payload is as measured or projected.
class CableEstimator final : public Estimator {
 public:
  CableEstimator(bool hybrid, TautPayload taut_payload, const EstimatorConfig& config,
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

  void OnImu(const ImuSample& imu) override {
    if (quad_.Predict(imu) != FilterStatus::kOk) return;
    TrackImu(imu);
    CheckHealth();
  }

  void OnVio(const VioSample& vio) override {
    quad_.UpdateVio(vio);
    if (vio.p_WB_W.allFinite() && vio.v_WB_W.allFinite() && vio.q_WB.coeffs().allFinite() &&
        std::isfinite(vio.time_s)) {
      last_vio_ = vio;
    }
    CheckHealth();
  }

  void OnAllocatedThrust(double thrust_N) override {
    if (std::isfinite(thrust_N)) {
      thrust_N_ = thrust_N;
    } else {
      ++thrust_commands_non_finite_;
    }
  }

  void OnPayloadDetection(const PayloadDetection& detection) override {
    TakeDetection(detection);
    CheckHealth();
  }

  SystemState Estimate(double time_s) const override {
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

  EstimatorHealth Health() const override {
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

 private:
  // The cable EKF, the tension cue and the slack hit check on one IMU sample the quadrotor
  // filter has taken.
  void TrackImu(const ImuSample& imu) {
    // while slack the taut process model does not hold: the cable EKF restarts at re-taut
    if (mode_ == CableMode::kTaut) {
      cable_.Predict(imu.time_s, thrust_N_, quad_.state().q_WB.toRotationMatrix());
    }
    // the tracked payload at this sample, predicted once for the tension cue and the hit check
    // (the cue restarts the tracker only from taut, when nothing was predicted yet)
    bool tracked = false;
    Eigen::Vector3d p_WL_W, v_WL_W;
    const auto track = [&] {
      if (!tracked) tracker_.PredictTo(imu.time_s, &p_WL_W, &v_WL_W);
      tracked = true;
    };
    if (hybrid_ && config_.tension_cue.enabled) {
      if (mode_ == CableMode::kSlack) track();
      UpdateTensionCue(imu, p_WL_W);
      // slack and out of sight, the tension back: the cable is taut again without a detection
      // (not for a payload last seen held up: a hand that holds it keeps the cable slack, and
      // the vehicle's own manoeuvres then move the tension estimate)
      if (tracked && mode_ == CableMode::kSlack && !tension_cue_.slack() && !support_.supported() &&
          UnseenFor(imu.time_s) > config_.tension_retaut_unseen_s) {
        RestartCableFromTracker(p_WL_W, v_WL_W);
        return;
      }
    }
    if (hybrid_ && mode_ == CableMode::kSlack && !tracker_hit_vehicle_) {
      // free fall through the vehicle: the payload has hit it, the prediction no longer holds
      const QuadFilterState& quad = quad_.state();
      track();
      const Eigen::Vector3d p_BL_B =
          quad.q_WB.toRotationMatrix().transpose() * (p_WL_W - quad.p_WB_W);
      const Eigen::Array3d reach_B = params_.body_half_size_m.array() + params_.payload_radius_m +
                                     config_.payload_hit_margin_m;
      tracker_hit_vehicle_ = (p_BL_B.cwiseAbs().array() < reach_B).all();
    }
  }

  // One camera frame's result: the mode decision, then the filter the mode says.
  void TakeDetection(const PayloadDetection& detection) {
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

  // Forced accepts and rejections of the payload tracker, forced accepts of the quadrotor
  // filter and health resets, summed: a change means a detection was an outlier, or the frame
  // the detections are located in jumped.
  int FrameJumps() const {
    return quad_.counts().forced_accepts + tracker_.counts().forced_accepts +
           tracker_.counts().rejected_updates + health_resets_.Total();
  }

  // Seconds since the newest detection taken (since the start before the first).
  double UnseenFor(double time_s) const {
    return time_s - (seen_ ? last_seen_time_s_ : initial_time_s_);
  }

  // The cable filter's covariance at a restart: the re-taut standard deviations per component.
  CableMatrix RetautCovariance() const {
    CableMatrix cov = CableMatrix::Zero();
    cov.diagonal() << Eigen::Vector3d::Constant(std::pow(config_.retaut_xi_std, 2)),
        Eigen::Vector3d::Constant(std::pow(config_.retaut_xi_dot_std_per_s, 2));
    return cov;
  }

  // The payload at time_s for a quadrotor at p_WQ_W, v_WQ_W, by the variant and the mode; true
  // when the slack prediction has run into the vehicle (the payload is then lost).
  bool PayloadAt(double time_s, const Eigen::Vector3d& p_WQ_W, const Eigen::Vector3d& v_WQ_W,
                 Eigen::Vector3d* p_WL_W, Eigen::Vector3d* v_WL_W) const {
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

  // The health check every input ends with: a state no filter may hand on (non-finite, a payload
  // faster relative to the vehicle than any push gives it, a cable stretched past its length
  // and the detector's error) re-initialises the filter that holds it, counted by cause.
  void CheckHealth() {
    const QuadFilterState& quad = quad_.state();
    if (!quad.p_WB_W.allFinite() || !quad.v_WB_W.allFinite() || !quad.q_WB.coeffs().allFinite() ||
        !quad.w_B_radps.allFinite() || !quad_.covariance().allFinite()) {
      if (!last_vio_) return;  // nothing to start from yet; Estimate falls back to the hover
      ++health_resets_.quad_non_finite;
      QuadFilterState from_vio;
      from_vio.time_s = last_vio_->time_s;
      from_vio.p_WB_W = last_vio_->p_WB_W;
      from_vio.v_WB_W = last_vio_->v_WB_W;
      from_vio.q_WB = last_vio_->q_WB;
      quad_ = QuadFilter(params_, config_.quad_filter, from_vio);
    }
    Eigen::Vector3d p_WL_W, v_WL_W;
    PayloadAt(quad.time_s, quad.p_WB_W, quad.v_WB_W, &p_WL_W, &v_WL_W);
    if (hybrid_ && mode_ == CableMode::kSlack) {
      // the tracker's own velocity at its last update (the sphere's hold in PayloadAt would hide
      // a wild one; the free fall since then adds g times a frame at most)
      v_WL_W = tracker_.state().tail<3>();
    }
    const Eigen::Vector3d d_W = p_WL_W - quad.p_WB_W;
    if (!p_WL_W.allFinite() || !v_WL_W.allFinite() || !cable_.covariance().allFinite() ||
        !tracker_.covariance().allFinite()) {
      ++health_resets_.payload_non_finite;
    } else if ((v_WL_W - quad.v_WB_W).norm() > config_.max_payload_relative_speed_mps) {
      ++health_resets_.payload_speed;
    } else if (d_W.norm() > params_.cable_length_m + config_.max_cable_stretch_m) {
      ++health_resets_.cable_length;
    } else {
      return;
    }
    ResetPayloadFromDetections(quad);
  }

  // The payload filters restarted from what the camera last saw: the newest detection's offset
  // from the vehicle if it is recent, else the payload hanging under the vehicle; at the
  // vehicle's velocity either way (a speed the detections cannot give).
  void ResetPayloadFromDetections(const QuadFilterState& quad) {
    const double l_m = params_.cable_length_m;
    Eigen::Vector3d d_W(0, 0, -l_m);
    const bool recent = has_last_detection_ &&
                        quad.time_s - last_detection_time_s_ <= config_.payload_lost_after_s &&
                        last_p_BL_B_.norm() > 1e-6;
    if (recent) {
      d_W = quad.q_WB * last_p_BL_B_;
      if (d_W.norm() > l_m) d_W *= l_m / d_W.norm();
    }
    const CableMatrix cable_cov = RetautCovariance();
    cable_.Reset(quad.time_s, d_W.normalized(), Eigen::Vector3d::Zero(), cable_cov);
    Matrix6d tracker_cov = Matrix6d::Zero();
    tracker_cov.diagonal() << Eigen::Vector3d::Constant(config_.initial_payload_position_var_m2),
        Eigen::Vector3d::Constant(std::pow(config_.slack_entry_velocity_std_mps, 2));
    tracker_.Reset(quad.time_s, quad.p_WB_W + d_W, quad.v_WB_W, tracker_cov);
    tracker_hit_vehicle_ = false;
    has_measured_ = false;
    measured_v_WL_W_.setZero();
    velocity_row_pending_ = false;
    rejected_xi_W_.clear();
    rejected_times_s_.clear();
  }

 private:
  // A detection carried to the body frame and, with the quadrotor's pose at its capture time,
  // to the world frame.
  struct LocatedDetection {
    double time_s;              // capture time
    Eigen::Vector3d p_BL_B;     // payload position, body frame
    Eigen::Matrix3d cov_B;      // its covariance, body frame
    QuadFilterState quad_then;  // the quadrotor filter's state at the capture time
    Eigen::Matrix3d R_WB;       // the attitude then
    Eigen::Vector3d p_WL_W;     // payload position, world frame
  };

  // The detection taken before the current one (for finite-difference velocities).
  struct PreviousDetection {
    bool valid;              // there was one
    Eigen::Vector3d p_WL_W;  // its payload position, world frame
    Eigen::Vector3d p_BL_B;  // the same in its body frame
    double time_s;           // its capture time
  };

  // The detection in body and world frames with the body-frame covariance of its position
  // (detection noise model plus floor), at the quadrotor pose of its capture time.
  LocatedDetection Locate(const PayloadDetection& detection) const {
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
  void EnterSlack(const LocatedDetection& d, const PreviousDetection& last,
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
  void RestartCableAtRetaut(const LocatedDetection& d) {
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

  // Re-taut flagged by the tension cue while the payload is out of sight: the cable EKF restarts
  // on the direction to the tracked payload with its velocity across the cable (Reset removes the
  // radial part, as in the inelastic collision of docs/design.md section 4).
  void RestartCableFromTracker(const Eigen::Vector3d& p_WL_W, const Eigen::Vector3d& v_WL_W) {
    const QuadFilterState& quad = quad_.state();
    const Eigen::Vector3d d_W = p_WL_W - quad.p_WB_W;
    const Eigen::Vector3d xi =
        d_W.norm() > 1e-6 ? Eigen::Vector3d(d_W.normalized()) : Eigen::Vector3d(0, 0, -1);
    const CableMatrix cov = RetautCovariance();
    cable_.Reset(quad.time_s, xi, (v_WL_W - quad.v_WB_W) / params_.cable_length_m, cov);
    mode_ = CableMode::kTaut;
    tension_entry_pending_ = false;
    velocity_row_pending_ = false;
    ++retaut_restarts_;
    ++retaut_restarts_by_tension_;
  }

  // The first detection after a re-taut restart fuses the rate of the body-frame payload position
  // between the restart's detection and this one, at the middle of their gap; the restart is at
  // the time the restart's detection arrived, later than its capture, so no earlier than that.
  void FuseRetautVelocity(const LocatedDetection& d, const PreviousDetection& last) {
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
  void UpdateTautCable(const LocatedDetection& d) {
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
  bool RejectedRunAgrees(const Eigen::Vector3d& xi_W) const {
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

  // Feeds the tension cue (p_L: the tracked payload at the sample, read while slack); a
  // taut-to-slack switch it flags starts the payload tracker from the cable EKF's payload state
  // at once (the next detection is up to a frame away).
  void UpdateTensionCue(const ImuSample& imu, const Eigen::Vector3d& p_L) {
    const QuadFilterState& quad = quad_.state();
    Eigen::Vector3d xi_W = cable_.xi_W();
    if (mode_ == CableMode::kSlack) {
      // the direction to the tracked payload (the cable EKF is frozen while slack)
      const Eigen::Vector3d d = p_L - quad.p_WB_W;
      if (d.norm() > 1e-6) xi_W = d.normalized();
    }
    tension_cue_.Update(imu.time_s, imu.accel_B_mps2 - quad.accel_bias_B_mps2,
                        quad.q_WB.toRotationMatrix(), thrust_N_, xi_W);
    if (mode_ != CableMode::kTaut || !tension_cue_.slack()) return;
    const double l_m = params_.cable_length_m;
    const Eigen::Vector3d p_WL_W = quad.p_WB_W + l_m * cable_.xi_W();
    const Eigen::Vector3d v_WL_W = quad.v_WB_W + l_m * cable_.xi_dot_W();
    // covariance: the cable EKF's, scaled by the length, plus the quadrotor's
    Matrix6d cov = Matrix6d::Zero();
    cov.block<3, 3>(0, 0) =
        l_m * l_m * cable_.covariance().block<3, 3>(0, 0) + quad_.covariance().block<3, 3>(0, 0);
    cov.block<3, 3>(3, 3) =
        l_m * l_m * cable_.covariance().block<3, 3>(3, 3) + quad_.covariance().block<3, 3>(3, 3);
    tracker_.Reset(imu.time_s, p_WL_W, v_WL_W, cov);
    mode_ = CableMode::kSlack;
    support_.Clear();
    slack_entered_at_s_ = imu.time_s;
    tension_entry_pending_ = true;
    ++slack_entries_;
    ++slack_entries_by_tension_;
  }

  // The measured payload: the newest detection in world and a low-passed finite difference of
  // consecutive detections (a first-order filter with time constant tau, alpha = dt/(tau + dt)).
  void UpdateMeasuredPayload(double time_s, const Eigen::Vector3d& p_WL_W) {
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

  static Eigen::Vector3d InitialXi(const SystemState& s, double l_m) {
    const Eigen::Vector3d d = s.p_WL_W - s.p_WQ_W;
    return d.norm() > 1e-6 ? Eigen::Vector3d(d.normalized()) : Eigen::Vector3d(0, 0, -1);
  }
  static Eigen::Vector3d InitialXiDot(const SystemState& s, double l_m) {
    const Eigen::Vector3d xi = InitialXi(s, l_m);
    const Eigen::Vector3d rel = (s.v_WL_W - s.v_WQ_W) / l_m;
    return rel - xi.dot(rel) * xi;
  }
  static CableMode InitialMode(bool hybrid, const Params& p, const SystemState& s) {
    if (!hybrid) return CableMode::kTaut;
    return (s.p_WL_W - s.p_WQ_W).norm() < p.cable_length_m - p.slack_epsilon_m ? CableMode::kSlack
                                                                               : CableMode::kTaut;
  }

  bool hybrid_;               // mode detector and payload tracker in use
  TautPayload taut_payload_;  // where the always-taut variants put the payload
  bool has_measured_ = false;
  Eigen::Vector3d measured_p_WL_W_ = Eigen::Vector3d::Zero();  // newest detection, world  (3)
  Eigen::Vector3d measured_v_WL_W_ = Eigen::Vector3d::Zero();  // low-passed, world  (3)
  double measured_time_s_ = 0.0;                               // capture time of the newest
  EstimatorConfig config_;
  Params params_;
  QuadFilter quad_;
  CableEkf cable_;
  ModeDetector mode_detector_;
  PayloadTracker tracker_;
  TensionCue tension_cue_;
  SupportDetector support_;           // slack: held up or falling, from the detections
  // a held payload's fitted motion is used only on detections captured after this (FrameJumps)
  double held_fit_after_s_ = -std::numeric_limits<double>::infinity();
  int frame_jumps_ = 0;  // FrameJumps() at the last slack detection
  double slack_entered_at_s_ = 0.0;   // when the last slack began (tension flag or detection)
  double thrust_N_;                   // last allocated collective thrust
  CableMode mode_;                    // estimated mode (always taut when !hybrid)
  bool payload_visible_ = true;       // last camera frame had a detection
  bool seen_ = false;                 // a detection has been taken since start
  double last_seen_time_s_ = 0.0;     // capture time of the newest detection taken
  double initial_time_s_ = 0.0;       // start time (the initial state counts as seen)
  bool tracker_hit_vehicle_ = false;  // the slack prediction ran into the vehicle since the
                                      // last detection
  bool has_last_detection_ = false;   // for the slack-entry velocity
  Eigen::Vector3d last_p_WL_W_ = Eigen::Vector3d::Zero();  // previous detection, world  (3)
  Eigen::Vector3d last_p_BL_B_ = Eigen::Vector3d::Zero();  // the same in its body frame  (3)
  bool velocity_row_pending_ = false;   // re-taut restart: the next detection fuses the velocity
  double restart_time_s_ = 0.0;         // time of the cable EKF's last re-taut restart
  double last_detection_time_s_ = 0.0;  // its capture time
  int detections_lost_ = 0;             // health counters (EstimatorHealth)
  int detections_non_finite_ = 0;
  int thrust_commands_non_finite_ = 0;
  int slack_entries_ = 0;
  int slack_entries_by_tension_ = 0;
  bool tension_entry_pending_ = false;  // slack flagged by tension, no detection since
  int retaut_restarts_ = 0;
  int retaut_restarts_by_tension_ = 0;
  int cable_reinitialisations_ = 0;
  EstimatorHealthResets health_resets_;  // the health check's re-initialisations by cause
  std::optional<VioSample> last_vio_;    // the newest finite VIO sample (the quad filter's restart)
  // directions (world) and capture times of the detections the cable EKF rejected in a row
  std::deque<Eigen::Vector3d> rejected_xi_W_;
  std::deque<double> rejected_times_s_;
};

}  // namespace

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
