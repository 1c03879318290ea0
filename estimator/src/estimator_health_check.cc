// The estimator's health check, which every input ends with (CableEstimator, cable_estimator.h): a
// state no filter may hand on re-initialises the filter that holds it, counted by cause, the
// payload filters restarting from what the camera last saw.

#include <cmath>

#include "cable_estimator.h"
#include "hpa/estimator/vehicle_filter.h"

namespace hpa {

// The health check every input ends with: a state no filter may hand on (non-finite, a payload
// faster relative to the vehicle than any push gives it, a cable stretched past its length
// and the detector's error) re-initialises the filter that holds it, counted by cause.
void CableEstimator::CheckHealth() {
  const QuadFilterState& quad = quad_.state();
  if (!QuadFilterFinite(quad_)) {
    if (!last_vio_) return;  // nothing to start from yet; Estimate falls back to the hover
    ++health_resets_.quad_non_finite;
    quad_ = QuadFilterFromVio(params_, config_.quad_filter, *last_vio_);
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
void CableEstimator::ResetPayloadFromDetections(const QuadFilterState& quad) {
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

}  // namespace hpa
