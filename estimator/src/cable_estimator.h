#pragma once
// The estimator behind MakeHybridEstimator and the always-taut variants (private to the estimator
// library): the quadrotor filter and the cable EKF, and when hybrid the mode detector and the
// free-fall payload tracker. Its parts, each in a file of its own: the interface and the estimate
// (estimator.cc), each IMU sample's prediction (estimator_prediction.cc), each camera frame's
// updates (estimator_updates.cc) and the health check every input ends with
// (estimator_health_check.cc).

#include <deque>
#include <limits>
#include <optional>

#include "hpa/estimator/estimator.h"

namespace hpa {

/// Where an always-taut estimator puts the payload.
enum class TautPayload {
  kMeasured,   // the detections' position and low-passed finite-difference velocity
  kProjected,  // on the cable sphere: x_Q + l xi from the cable EKF
};

/// Quadrotor filter + cable EKF, and when hybrid the mode detector and the free-fall payload
/// tracker; not hybrid, the mode is always taut and the payload is as measured or projected.
class CableEstimator final : public Estimator {
 public:
  /// The estimator of a variant (hybrid or always taut, and then where its payload is) started at
  /// `initial`.
  CableEstimator(bool hybrid, TautPayload taut_payload, const EstimatorConfig& config,
                 const Params& params, const SystemState& initial);

  /// Estimator's interface (hpa/estimator/estimator.h).
  void OnImu(const ImuSample& imu) override;
  void OnVio(const VioSample& vio) override;
  void OnAllocatedThrust(double thrust_N) override;
  void OnPayloadDetection(const PayloadDetection& detection) override;
  SystemState Estimate(double time_s) const override;
  EstimatorHealth Health() const override;

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

  // ---- the estimate (estimator.cc) ----

  // Forced accepts and rejections of the payload tracker, forced accepts of the quadrotor
  // filter and health resets, summed: a change means a detection was an outlier, or the frame
  // the detections are located in jumped.
  int FrameJumps() const;

  // Seconds since the newest detection taken (since the start before the first).
  double UnseenFor(double time_s) const;

  // The cable filter's covariance at a restart: the re-taut standard deviations per component.
  CableMatrix RetautCovariance() const;

  // The payload at time_s for a quadrotor at p_WQ_W, v_WQ_W, by the variant and the mode; true
  // when the slack prediction has run into the vehicle (the payload is then lost).
  bool PayloadAt(double time_s, const Eigen::Vector3d& p_WQ_W, const Eigen::Vector3d& v_WQ_W,
                 Eigen::Vector3d* p_WL_W, Eigen::Vector3d* v_WL_W) const;

  // The cable direction of a state (straight down when the payload is at the vehicle).
  static Eigen::Vector3d InitialXi(const SystemState& s, double l_m);
  // The cable direction's rate of a state: the relative velocity across the cable over l_m.
  static Eigen::Vector3d InitialXiDot(const SystemState& s, double l_m);
  // The mode a state starts in: slack when hybrid and the payload is within l - epsilon.
  static CableMode InitialMode(bool hybrid, const Params& p, const SystemState& s);

  // ---- each IMU sample (estimator_prediction.cc) ----

  // The cable EKF, the tension cue and the slack hit check on one IMU sample the quadrotor
  // filter has taken.
  void TrackImu(const ImuSample& imu);

  // Feeds the tension cue (p_L: the tracked payload at the sample, read while slack); a
  // taut-to-slack switch it flags starts the payload tracker from the cable EKF's payload state
  // at once (the next detection is up to a frame away).
  void UpdateTensionCue(const ImuSample& imu, const Eigen::Vector3d& p_L);

  // Re-taut flagged by the tension cue while the payload is out of sight: the cable EKF restarts
  // on the direction to the tracked payload with its velocity across the cable (Reset removes the
  // radial part, as in the inelastic collision of docs/design.md section 4).
  void RestartCableFromTracker(const Eigen::Vector3d& p_WL_W, const Eigen::Vector3d& v_WL_W);

  // ---- each camera frame (estimator_updates.cc) ----

  // One camera frame's result: the mode decision, then the filter the mode says.
  void TakeDetection(const PayloadDetection& detection);

  // The detection in body and world frames with the body-frame covariance of its position
  // (detection noise model plus floor), at the quadrotor pose of its capture time.
  LocatedDetection Locate(const PayloadDetection& detection) const;

  // Enters slack at a detection: starts the free-fall tracker there, its velocity from the last
  // two detections (free fall between them) when recent, else from the taut model.
  void EnterSlack(const LocatedDetection& d, const PreviousDetection& last,
                  const Eigen::Matrix3d& cov_W, bool entered_by_tension);

  // Re-taut: restarts the cable EKF on the measured direction and the tracker's velocity (radial
  // part removed, as in the inelastic collision of docs/design.md section 4).
  void RestartCableAtRetaut(const LocatedDetection& d);

  // The first detection after a re-taut restart fuses the rate of the body-frame payload position
  // between the restart's detection and this one, at the middle of their gap; the restart is at
  // the time the restart's detection arrived, later than its capture, so no earlier than that.
  void FuseRetautVelocity(const LocatedDetection& d, const PreviousDetection& last);

  // A taut detection to the cable EKF. A run of rejected detections that agree with each other
  // means the filter has diverged (e.g. on a thrust it was wrongly told), not the camera: it
  // restarts from the detections rather than lock them out or fuse one into a filter that is
  // sure of the wrong state.
  void UpdateTautCable(const LocatedDetection& d);

  // Whether the rejected run and `xi_W` agree with each other: a smooth swing (successive
  // directions within kAgreeRad, about a 10 rad/s swing between 30 Hz frames), not outliers.
  bool RejectedRunAgrees(const Eigen::Vector3d& xi_W) const;

  // The measured payload: the newest detection in world and a low-passed finite difference of
  // consecutive detections (a first-order filter with time constant tau, alpha = dt/(tau + dt)).
  void UpdateMeasuredPayload(double time_s, const Eigen::Vector3d& p_WL_W);

  // ---- the health check (estimator_health_check.cc) ----

  // The health check every input ends with: a state no filter may hand on (non-finite, a payload
  // faster relative to the vehicle than any push gives it, a cable stretched past its length
  // and the detector's error) re-initialises the filter that holds it, counted by cause.
  void CheckHealth();

  // The payload filters restarted from what the camera last saw: the newest detection's offset
  // from the vehicle if it is recent, else the payload hanging under the vehicle; at the
  // vehicle's velocity either way (a speed the detections cannot give).
  void ResetPayloadFromDetections(const QuadFilterState& quad);

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
  SupportDetector support_;  // slack: held up or falling, from the detections
  // a held payload's fitted motion is used only on detections captured after this (FrameJumps)
  double held_fit_after_s_ = -std::numeric_limits<double>::infinity();
  int frame_jumps_ = 0;               // FrameJumps() at the last slack detection
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

}  // namespace hpa
