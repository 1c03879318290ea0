#pragma once
// The onboard estimator as the runner sees it: sensor messages in, SystemState out.
// Same output type as ground truth, so the scenario's ground-truth switch changes the source only.

#include <memory>

#include "hpa/estimator/cable_ekf.h"
#include "hpa/estimator/estimator_health.h"
#include "hpa/estimator/mode_detector.h"
#include "hpa/estimator/payload_tracker.h"
#include "hpa/estimator/quad_filter.h"
#include "hpa/estimator/support_detector.h"
#include "hpa/estimator/tension_cue.h"
#include "hpa/models/detection_noise.h"
#include "hpa/models/params.h"
#include "hpa/models/sensor_types.h"
#include "hpa/models/state.h"

namespace hpa {

/// Settings of the estimator; the defaults are the tuned values.
struct EstimatorConfig {
  QuadFilterConfig quad_filter;            // IMU + VIO error-state EKF
  CableEkfConfig cable_ekf;                // (xi, xi_dot) EKF
  ModeDetectorConfig mode_detector;        // low-pass cable length vs l - epsilon
  TensionCueConfig tension_cue;            // slack from the IMU-implied cable tension
  PayloadTrackerConfig payload_tracker;    // free-fall payload filter used while slack
  SupportDetectorConfig support_detector;  // slack: held up or falling
  CameraNoiseModel detection_noise;        // detector noise -> measurement covariances
  double detection_noise_floor_m = 0.002;  // added per axis (attitude and sync errors)
  // payload tracker covariance at start, per axis (variances: the tuned values are exact there)
  double initial_payload_position_var_m2 = 1e-4;
  double initial_payload_velocity_var_m2ps2 = 1e-2;
  // slack entry: the payload velocity comes from the last two detections (free fall between
  // them) when they are between these gaps apart, else from the taut model with this std
  double slack_entry_min_detection_gap_s = 1e-3;  // closer: the difference is noise
  double slack_entry_max_detection_gap_s = 0.1;   // farther: the older one predates the event
  double slack_entry_velocity_std_mps = 0.5;      // taut-model velocity's std, per axis
  // re-taut: the cable EKF restarts on the measured direction with this std, per axis
  double retaut_xi_std = 0.03;           // unit-vector components
  double retaut_xi_dot_std_per_s = 1.0;  // cable direction rate
  // the cable EKF's velocity row (the paper's Z second row): on the first detection after a
  // re-taut restart, the finite difference with the restart's detection, fused at the middle of
  // their gap (later detections would count a fused one twice); false: position row only
  bool retaut_velocity_row = true;
  double max_extrapolation_s = 0.05;  // Estimate() ahead of the last IMU sample, at most
  // always_taut (the paper's baseline): the payload state as measured, not projected on the cable
  double measured_velocity_time_constant_s = 0.1;  // low-pass on the detections' finite difference
  double measured_velocity_max_gap_s = 0.1;  // longer gaps between detections: no new difference
  double measured_payload_max_age_s = 0.2;   // older detection: fall back to x_Q + l xi
  // the payload is reported lost (SystemState::payload_lost) when no detection has been taken
  // for this long. Ours, not tuned: six frames at 30 Hz, well past the single frames lost when
  // the cable crosses the ball
  double payload_lost_after_s = 0.2;
  // while slack, the payload is also lost when the free-fall prediction comes within the
  // vehicle's collision box grown by the payload radius and this margin: the payload has hit
  // the vehicle and free fall no longer holds
  double payload_hit_margin_m = 0.01;
  // slack, the payload unseen for longer than this and the tension cue taut again: the cable is
  // taut without a detection (three frames at 30 Hz: the camera has had its chance to say so)
  double tension_retaut_unseen_s = 0.1;
  // the health check (re-initialise from the detections) refuses a payload faster than this
  // relative to the vehicle: the largest push the shipped sweeps draw, 2.5 N s, gives the 0.1 kg
  // payload 25 m/s, a fall from the arena's 10 m ceiling 14 m/s, the vehicle itself a few m/s
  double max_payload_relative_speed_mps = 40.0;
  // ... or farther from the vehicle than the cable's length plus this: the tendon's stretch at
  // the hardest re-taut is centimetres, the detector's error at 0.5 m millimetres
  double max_cable_stretch_m = 0.1;
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
  /// Collective thrust (N) the rate loop's allocation produced (PX4 publishes it: after a
  /// saturated mixer has lowered it, not the MPC's command), for the cable EKF's process model
  /// and the tension cue.
  virtual void OnAllocatedThrust(double thrust_N) = 0;
  /// Current estimate at time_s (mode included).
  virtual SystemState Estimate(double time_s) const = 0;
  /// Counts of what the filters did with their inputs since start, and the mode state.
  virtual EstimatorHealth Health() const = 0;
};

}  // namespace hpa
