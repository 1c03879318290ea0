#pragma once
// The onboard estimator as the runner sees it: sensor messages in, SystemState out.
// Same output type as ground truth, so the scenario's ground-truth switch changes the source only.

#include <memory>

#include "hpa/estimator/analytic_camera.h"
#include "hpa/estimator/cable_ekf.h"
#include "hpa/estimator/mode_detector.h"
#include "hpa/estimator/payload_tracker.h"
#include "hpa/estimator/quad_filter.h"
#include "hpa/models/params.h"
#include "hpa/models/sensor_types.h"
#include "hpa/models/state.h"

namespace hpa {

/// Settings of the estimator from the scenario's `estimation:` block.
struct EstimatorConfig {
  bool hybrid = true;  // true: mode detector (hpa_mpc); false: always taut (nonhybrid_mpc)
  // Added by the estimator issue (defaults are the tuned values; scenarios need not set them):
  QuadFilterConfig quad_filter;            // IMU + VIO error-state EKF
  CableEkfConfig cable_ekf;                // (xi, xi_dot) EKF
  ModeDetectorConfig mode_detector;        // low-pass cable length vs l - epsilon
  PayloadTrackerConfig payload_tracker;    // free-fall payload filter used while slack
  CameraNoiseModel detection_noise;        // detector noise -> measurement covariances
  double detection_noise_floor_m = 0.002;  // added per axis (attitude and sync errors)
};

/// Full onboard estimator: quadrotor filter (IMU + VIO), cable EKF, mode detector.
class Estimator {
 public:
  virtual ~Estimator() = default;
  /// IMU sample at 500 Hz: predicts the quadrotor filter and the cable EKF.
  virtual void OnImu(const ImuSample& imu) = 0;
  /// VIO pose at 30 Hz (stamped at capture; may arrive late).
  virtual void OnVio(const VioSample& vio) = 0;
  /// Camera frame result at 30 Hz (detector or analytic camera), stamped at capture.
  virtual void OnPayloadDetection(const PayloadDetection& detection) = 0;
  /// Collective thrust command (N) sent to the vehicle, for the cable EKF's process model.
  virtual void OnThrustCommand(double thrust_N) = 0;
  /// Current estimate at time_s (mode included).
  virtual SystemState Estimate(double time_s) const = 0;
};

/// Builds the estimator; `initial` is the state it starts from (the vehicle at rest on start).
std::unique_ptr<Estimator> MakeEstimator(const EstimatorConfig& config, const Params& params,
                                         const SystemState& initial);

}  // namespace hpa
