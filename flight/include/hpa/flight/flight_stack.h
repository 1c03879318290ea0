#pragma once
// The flight stack as one unit: the payload detector, the estimator and the high-level controller
// fed, tick by tick of the lockstep clock, with what reaches a vehicle's flight computer (IMU,
// VIO, camera frames or detections, the rate loop's allocated thrust) and answering with its
// estimate and, at its control rate, a body-rate + thrust command. The simulator drives it in
// process or, through the lockstep protocol (protocol.h), as the separate hpa-flight binary;
// both run this class, so the two give the same run. No MuJoCo or GL here.

#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "hpa/controller/controller.h"
#include "hpa/controller/reference_spec.h"
#include "hpa/estimator/estimator_health.h"
#include "hpa/estimator/payload_detector.h"
#include "hpa/models/camera_frame.h"
#include "hpa/models/lockstep.h"
#include "hpa/models/params.h"
#include "hpa/models/sensor_types.h"
#include "hpa/models/state.h"

namespace hpa {
class Estimator;
}  // namespace hpa

namespace hpa::flight {

class ControlThread;

/// Everything the flight stack is built from: the flight code's model of its vehicle and task.
struct FlightConfig {
  Params params;                     // the flight code's params (not the world's mismatch)
  ControllerConfig controller;       // registered controller and its settings
  std::string estimator = "hybrid";  // registered estimator name
  bool slack_tension_cue = true;     // the hybrid estimator also flags slack from the IMU tension
  ReferenceSpec reference;           // the payload reference
  bool ground_truth = false;         // the scenario's ground-truth switch: the state is the truth
  double estimate_latency_s = 0.0;   // the controller reads an estimate this old
  double tick_hz = 1000.0;           // the lockstep clock's rate (the simulator's physics rate)
  SystemState initial_state;         // where the estimator starts
  // the controller's update runs on a thread of its own, beside the simulation, its command
  // taken with AwaitCommand (the same command: only when it is computed changes); in process
  // only, not part of the lockstep protocol
  bool control_thread = false;
};

/// The rate loop's last allocation: the thrust the mixer made, not the one commanded.
struct AllocationReport {
  double thrust_allocated_N = 0.0;  // collective thrust of the allocated rotor speeds
  bool saturated = false;           // the allocation fell short of the command
};

/// The rendered frame the simulator hands over (models/camera_frame.h), under the flight code's
/// name for it (the protocol's tick carries its capture time, region and ring slots).
using hpa::CameraFrame;

/// The payload reference at one tick, for flight stacks that do not build their own.
struct ReferenceSample {
  Eigen::Vector3d p_WL_W = Eigen::Vector3d::Zero();  // payload position  (3)
  Eigen::Vector3d v_WL_W = Eigen::Vector3d::Zero();  // payload velocity  (3)
  Eigen::Vector3d a_WL_W = Eigen::Vector3d::Zero();  // payload acceleration  (3)
};

/// What reaches the flight computer at one tick, processed in this order: the allocation, IMU,
/// VIO, detections, frames.
struct FlightInputs {
  double time_s = 0.0;
  std::optional<AllocationReport> allocation;  // the rate loop ran since the last tick
  std::vector<ImuSample> imu;
  std::vector<VioSample> vio;
  std::vector<PayloadDetection> detections;  // the analytic camera, or detected in the simulator
  std::vector<CameraFrame> frames;           // rendered frames to detect here
  std::optional<SystemState> truth;          // the ground-truth switch only
  bool need_estimate = false;                // the simulator reads the estimate at this tick
  bool gripper_active = false;               // a gripper holds the payload (information only)
  ReferenceSample reference;                 // the payload reference now (information only)
  bool no_reply = false;  // the simulator reads no reply to this tick (protocol flag no_reply)

  /// Back to a tick with no inputs (as a default FlightInputs), the lists keeping their storage.
  void Clear() {
    time_s = 0.0;
    allocation.reset();
    imu.clear();
    vio.clear();
    detections.clear();
    frames.clear();
    truth.reset();
    need_estimate = false;
    gripper_active = false;
    reference = ReferenceSample();
    no_reply = false;
  }
};

/// What the flight computer answers at one tick.
struct FlightOutputs {
  bool has_command = false;      // a control step ran at this tick
  bool command_pending = false;  // it runs on the control thread: AwaitCommand gives `command`
  ControlOutput command;         // its command (has_command and not command_pending)
  bool has_estimate = false;
  SystemState estimate;                // the state the flight code acts on now (has_estimate)
  int estimator_rejected_updates = 0;  // estimator health after this tick (0 with ground truth)
  int estimator_resets = 0;
  // the health check's re-initialisations so far by cause (none with ground truth)
  std::optional<EstimatorHealthResets> estimator_health_resets;
  int frames_detected = 0;  // of this tick's frames, those in which the payload was found
  // the region the camera should read out next, around the detections delivered so far (empty:
  // the whole frame)
  cv::Rect camera_roi;
};

/// Estimator health as named numbers (metrics.json's estimator_health), in a fixed order.
using HealthFields = std::vector<std::pair<std::string, double>>;

/// The detector + estimator + controller of one run, stepped on the lockstep clock.
class FlightStack {
 public:
  /// Builds the registered controller and estimator of `config`; throws std::invalid_argument
  /// for an unknown name.
  explicit FlightStack(const FlightConfig& config);
  ~FlightStack();
  FlightStack(const FlightStack&) = delete;
  FlightStack& operator=(const FlightStack&) = delete;

  /// One tick: delivers `in`'s messages, then estimates and, when its control loop fires,
  /// computes a command (with config().control_thread: starts computing it, command_pending).
  /// Call once per tick of the clock, from tick 0.
  FlightOutputs Step(const FlightInputs& in);
  /// The command of the oldest pending control step, once computed (waits for it); rethrows
  /// what the controller threw. Throws std::logic_error when none is pending.
  ControlOutput AwaitCommand();
  /// Delivers `in`'s sensor messages only; returns how many of its frames had the payload.
  int Deliver(const FlightInputs& in);
  /// The end of a run: delivers `in`'s sensor messages (those of the last physics step) and
  /// only detects its frames (captured, not yet delivered); returns how many had the payload.
  int Finish(const FlightInputs& in);
  /// The region the camera should read out next (FlightOutputs::camera_roi as the last Step
  /// gave it; empty: the whole frame, or no detector).
  cv::Rect CameraRegion() const;
  /// Detects in a frame at its capture, reading what of it is read out (DetectFrame's order):
  /// the detection, or nullopt when the region cannot decide and the whole frame is not read
  /// out yet.
  std::optional<PayloadDetection> DetectCaptured(const CameraFrame& frame) const;
  /// Detects in a frame at its capture (DetectFrame's order): its region first, the whole frame
  /// of the same exposure, read with `read_whole`, only when the region cannot decide.
  PayloadDetection DetectCaptured(const CameraFrame& frame,
                                  const WholeFrameReader& read_whole) const;
  /// The estimator's health counters (empty with ground truth).
  HealthFields EstimatorHealth() const;
  /// The controller's rate (Hz): the flight code declares it.
  double control_rate_hz() const;
  const FlightConfig& config() const { return config_; }

 private:
  FlightConfig config_;
  std::unique_ptr<Controller> controller_;
  std::unique_ptr<Estimator> estimator_;
  std::unique_ptr<PayloadDetector> detector_;
  LockstepClock clock_;
  int control_loop_ = -1;
  DelayLine<SystemState> estimates_in_flight_;
  SystemState delayed_state_;  // latest estimate old enough to have reached the controller
  bool have_delayed_state_ = false;
  // the last two detections delivered (the camera's, or its own in delivered frames): the region
  // of interest of the next frame follows them (FlightOutputs::camera_roi)
  RecentDetections recent_detections_;
  std::unique_ptr<ControlThread> control_thread_;  // config_.control_thread only
};

/// Detects the payload in a frame: in its region of interest first, in the whole frame when the
/// region cannot decide: frame.whole_bgr, or, when the frame does not hold it, the image
/// `read_whole` reads out (if given). The one read-out order of both camera paths.
PayloadDetection DetectFrame(const PayloadDetector& detector, const CameraFrame& frame,
                             const WholeFrameReader& read_whole = nullptr);

/// How far (pixels) the payload's image may move between two frames and stay in the region
/// around its last detection.
constexpr double kRegionMarginPx = 48.0;

}  // namespace hpa::flight
