#pragma once
// A vehicle's onboard estimate of its own state alone (a team vehicle's: its payload's state comes
// from motion capture): the quadrotor filter (quad_filter.h) on the vehicle's IMU and VIO, with
// the quadrotor part of the single vehicle's health check, so it never hands on a non-finite
// state.

#include <optional>

#include "hpa/estimator/quad_filter.h"
#include "hpa/models/params.h"
#include "hpa/models/sensor_types.h"

namespace hpa {

/// Whether a VIO sample can restart a filter (every number finite).
bool VioUsable(const VioSample& vio);

/// Whether the quadrotor filter's state and covariance are finite (the health check's test).
bool QuadFilterFinite(const QuadFilter& quad);

/// The health check's restart: a quadrotor filter started at the VIO sample's time, pose and
/// velocity.
QuadFilter QuadFilterFromVio(const Params& params, const QuadFilterConfig& config,
                             const VioSample& vio);

/// A vehicle's own state from its IMU and VIO: the quadrotor filter and its health check.
class VehicleFilter {
 public:
  /// Starts at `initial` (the vehicle's known start, as the single vehicle's estimator does).
  VehicleFilter(const Params& params, const QuadFilterConfig& config,
                const QuadFilterState& initial);
  /// An IMU sample: predicts, then the health check.
  void OnImu(const ImuSample& imu);
  /// A VIO sample (stamped at capture; may arrive late): updates, then the health check.
  void OnVio(const VioSample& vio);
  /// The estimate at time_s: the filter's state moved ahead at its velocity by at most
  /// max_ahead_s past its last IMU sample (the single vehicle's Estimate does the same); always
  /// finite (the start state while the filter's state or covariance is non-finite and no VIO
  /// sample has come to restart it from).
  QuadFilterState Estimate(double time_s, double max_ahead_s) const;
  /// How often the health check restarted the filter.
  int restarts() const { return restarts_; }
  /// What the filter did with its inputs.
  const FilterCounts& counts() const { return quad_.counts(); }

 private:
  Params params_;
  QuadFilterConfig config_;
  QuadFilter quad_;
  QuadFilterState initial_;
  std::optional<VioSample> last_vio_;  // the newest finite VIO sample (the restart's)
  int restarts_ = 0;

  void CheckHealth();  // a non-finite filter restarts from last_vio_
};

}  // namespace hpa
