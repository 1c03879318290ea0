// VehicleFilter: the quadrotor filter with its health check, and that check as one function the
// single vehicle's estimator uses too.

#include "hpa/estimator/vehicle_filter.h"

#include <algorithm>
#include <cmath>

namespace hpa {

bool VioUsable(const VioSample& vio) {
  return vio.p_WB_W.allFinite() && vio.v_WB_W.allFinite() && vio.q_WB.coeffs().allFinite() &&
         std::isfinite(vio.time_s);
}

bool QuadFilterFinite(const QuadFilter& quad) {
  const QuadFilterState& s = quad.state();
  return s.p_WB_W.allFinite() && s.v_WB_W.allFinite() && s.q_WB.coeffs().allFinite() &&
         s.w_B_radps.allFinite() && quad.covariance().allFinite();
}

QuadFilter QuadFilterFromVio(const Params& params, const QuadFilterConfig& config,
                             const VioSample& vio) {
  QuadFilterState from_vio;
  from_vio.time_s = vio.time_s;
  from_vio.p_WB_W = vio.p_WB_W;
  from_vio.v_WB_W = vio.v_WB_W;
  from_vio.q_WB = vio.q_WB;
  return QuadFilter(params, config, from_vio);
}

VehicleFilter::VehicleFilter(const Params& params, const QuadFilterConfig& config,
                             const QuadFilterState& initial)
    : params_(params), config_(config), quad_(params, config, initial), initial_(initial) {}

void VehicleFilter::OnImu(const ImuSample& imu) {
  if (quad_.Predict(imu) != FilterStatus::kOk) return;
  CheckHealth();
}

void VehicleFilter::OnVio(const VioSample& vio) {
  quad_.UpdateVio(vio);
  if (VioUsable(vio)) last_vio_ = vio;
  CheckHealth();
}

void VehicleFilter::CheckHealth() {
  if (QuadFilterFinite(quad_) || !last_vio_) return;
  quad_ = QuadFilterFromVio(params_, config_, *last_vio_);
  ++restarts_;
}

QuadFilterState VehicleFilter::Estimate(double time_s, double max_ahead_s) const {
  // a filter the health check could not restart yet (no VIO): the known start, never its state
  QuadFilterState out = QuadFilterFinite(quad_) ? quad_.state() : initial_;
  const double ahead_s = std::clamp(time_s - out.time_s, 0.0, max_ahead_s);
  out.p_WB_W += out.v_WB_W * ahead_s;
  out.time_s = time_s;
  return out;
}

}  // namespace hpa
