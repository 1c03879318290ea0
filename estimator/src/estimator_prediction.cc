// The estimator's prediction on each IMU sample the quadrotor filter has taken (CableEstimator,
// cable_estimator.h): the cable EKF's prediction while taut, the tension cue with the slack entry
// and the re-taut out of sight it flags, and the check that the slack prediction has run into
// the vehicle.

#include <cmath>

#include "cable_estimator.h"

namespace hpa {

// The cable EKF, the tension cue and the slack hit check on one IMU sample the quadrotor
// filter has taken.
void CableEstimator::TrackImu(const ImuSample& imu) {
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
    const Eigen::Array3d reach_B =
        params_.body_half_size_m.array() + params_.payload_radius_m + config_.payload_hit_margin_m;
    tracker_hit_vehicle_ = (p_BL_B.cwiseAbs().array() < reach_B).all();
  }
}

// Feeds the tension cue (p_L: the tracked payload at the sample, read while slack); a
// taut-to-slack switch it flags starts the payload tracker from the cable EKF's payload state
// at once (the next detection is up to a frame away).
void CableEstimator::UpdateTensionCue(const ImuSample& imu, const Eigen::Vector3d& p_L) {
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

// Re-taut flagged by the tension cue while the payload is out of sight: the cable EKF restarts
// on the direction to the tracked payload with its velocity across the cable (Reset removes the
// radial part, as in the inelastic collision of docs/design.md section 4).
void CableEstimator::RestartCableFromTracker(const Eigen::Vector3d& p_WL_W,
                                             const Eigen::Vector3d& v_WL_W) {
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

}  // namespace hpa
