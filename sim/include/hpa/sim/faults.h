#pragma once
// Faults of the world's sensors and actuators (docs/faults.md): PX4's `failure <component>
// <type>` vocabulary where it fits. The world holds one Faults component and reaches it through
// World::faults(); a fault changes what a sensor delivers or what an actuator does, never the
// flight code's state, so a separate flight stack receives the faulty data through the protocol
// as the in-process stack does. Every component, mode and key is declared once in
// FaultComponents(): the scenario's fault event reads it and `hpa schema faults` prints it. A new
// fault is a row there and its effect in faults.cc; the world does not change.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <deque>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "hpa/models/params.h"
#include "hpa/models/state.h"
#include "hpa/sim/payload_camera.h"
#include "hpa/sim/sensors.h"

namespace hpa::sim {

/// What a fault acts on.
enum class FaultComponent { kVio, kImu, kRateGyro, kMotor, kGripper, kCamera };

/// How it fails.
enum class FaultMode {
  kOff,           // no samples (frames) at all
  kStuck,         // the first sample (frame) of the fault, again and again
  kWrong,         // VIO: its position jumped by an offset
  kDelayed,       // delivered `delay` s later than declared
  kSlow,          // a lower rate
  kIntermittent,  // samples dropped at a rate
  kGarbage,       // camera: a noise image
  kBias,          // a bias step
  kNoise,         // a burst of white noise
  kLoss,          // motor: loss of effectiveness
  kEarly,         // gripper: lets go on its own, at the fault's start
  kLate,          // gripper: a release commanded in the fault's window waits for its end
  kDistractor,    // camera: a second object that looks like the payload, in the rendered scene
};

/// One fault injected into the world: its component, mode, window and the mode's values.
struct Fault {
  FaultComponent component = FaultComponent::kVio;
  FaultMode mode = FaultMode::kOff;
  double start_s = 0.0;                                         // simulated time it starts
  double end_s = std::numeric_limits<double>::infinity();       // and ends (inf: never)
  Eigen::Vector3d offset_W_m = Eigen::Vector3d::Zero();         // VIO wrong: position jump  (3)
  double delay_s = 0.0;                                         // delayed: extra latency
  double rate_hz = 0.0;                                         // slow: the lower rate
  double drop_fraction = 0.0;                                   // intermittent: share dropped
  Eigen::Vector3d gyro_bias_B_radps = Eigen::Vector3d::Zero();  // bias step  (3)
  Eigen::Vector3d accel_bias_B_mps2 = Eigen::Vector3d::Zero();  // bias step (IMU)  (3)
  double gyro_noise_radps = 0.0;  // noise burst: standard deviation per sample
  double accel_noise_mps2 = 0.0;  // noise burst (IMU): standard deviation per sample
  double motor = 0.0;             // motor: rotor index 0-3 (PX4's -i, from 0)
  double loss = 1.0;              // motor: share of thrust lost, 0-1 (off: 1)
  Eigen::Vector3d distractor_W_m = Eigen::Vector3d::Zero();             // where it starts  (3)
  Eigen::Vector3d distractor_velocity_W_mps = Eigen::Vector3d::Zero();  // how it moves  (3)
  double distractor_visible_fraction = 1.0;  // distractor: probability it is drawn in a frame
};

/// What one camera fault's frames showed, counted at capture over its window: how often a
/// distractor was drawn and in the image, and how many detections landed on it (a found
/// detection whose bearing is closer to a drawn distractor's centre than to the payload's).
struct FaultFrameTally {
  double start_s = 0.0;              // the fault's start (which fault it is, with the order)
  bool distractor = false;           // a distractor fault (the other counts stay 0 otherwise)
  int frames = 0;                    // captures in its window
  int drawn_frames = 0;              // of them, with the distractor drawn
  int in_image_frames = 0;           // with it drawn and its centre inside the image
  int detections = 0;                // found detections made at capture in its window
  int detections_on_distractor = 0;  // of them, on the distractor rather than the payload
};

/// One key a fault mode reads besides at, type, component, mode and duration.
struct FaultKeyDecl {
  std::string key;          // as written in the event
  std::string unit;         // "s", "m", "1", ...
  std::string description;  // one line
  double min = 0.0, max = 0.0;
  std::optional<double> fallback;            // default (none: required); vectors: each entry
  double Fault::*number = nullptr;           // a scalar's field (or nullptr)
  Eigen::Vector3d Fault::*vector = nullptr;  // a 3-vector's field (or nullptr)
  bool integer = false;                      // a whole number
};

/// One mode of a component, declared once.
struct FaultModeDecl {
  FaultMode mode;
  std::string name;         // as written in the event (`mode:`)
  std::string px4;          // the PX4 `failure` command it mirrors, or "" for none
  std::string description;  // what it does, one line
  std::vector<FaultKeyDecl> keys;
  bool has_duration = true;  // false: an instant (gripper early)
};

/// One component with its modes.
struct FaultComponentDecl {
  FaultComponent component;
  std::string name;         // as written in the event (`component:`)
  std::string description;  // what it is
  std::vector<FaultModeDecl> modes;
};

/// Every fault component and mode, in order (the one declaration).
const std::vector<FaultComponentDecl>& FaultComponents();

/// The world's active faults and what they do to its sensor streams and actuators.
class Faults {
 public:
  /// Faults of a run seeded `run_seed`: each injected fault draws from its own stream of it.
  explicit Faults(uint64_t run_seed);
  /// Removes every fault (World::Reset).
  void Clear();
  /// Injects `fault` (its window from start_s to end_s); the i-th injected fault's randomness is
  /// the i-th stream of the run seed.
  void Inject(const Fault& fault);
  /// No fault was injected since Clear (the world then skips every fault hook).
  bool empty() const { return faults_.empty(); }

  /// Applies the sensor faults to messages delivered at `now_s` (in place: dropped, changed,
  /// held back), and appends the held messages whose time has come.
  void FilterDelivered(double now_s, std::vector<SensorMessage>* messages);
  /// Appends every message still held back (the end of a run), in order.
  void TakeHeld(std::vector<SensorMessage>* out);
  /// Applies the camera's pixel faults (stuck, garbage) to a capture at `now_s`: its detection,
  /// or its frames, replaced; a rendered in-process frame's noise is detected through `readout`.
  /// `truth` and `world_params` (the true state and camera mount) classify each detection made
  /// at capture against the distractors drawn in the frame (FrameTallies).
  void OnCameraCapture(double now_s, const SystemState& truth, const Params& world_params,
                       CameraReadout* readout, std::optional<PayloadDetection>* detection,
                       std::optional<CameraFrame>* frames, CameraCapture* capture);
  /// Each rotor's thrust factor at `now_s` (1: healthy) into `factor`; false when no motor fault
  /// was injected (factor untouched).
  bool MotorThrustFactors(double now_s, Eigen::Vector4d* factor) const;
  /// True when a release commanded at `now_s` must wait (a late gripper); it then happens when
  /// TakeGripperRelease says so.
  bool DefersRelease(double now_s);
  /// True once when the gripper lets go on its own at `now_s` (early, or a late one's end).
  bool TakeGripperRelease(double now_s);
  /// Where the camera's distractors drawn at `now_s` are (m, world frame): the rendered scene
  /// draws a copy of the payload at each. Whether a flickering distractor is drawn is a draw
  /// keyed by `now_s` from its fault's stream, so every render of one instant agrees.
  std::vector<std::array<double, 3>> DistractorPositions_W(double now_s) const;
  /// One tally per injected fault, in the order injected (the distractor counts for a
  /// distractor fault, zeros for the others).
  std::vector<FaultFrameTally> FrameTallies() const;

 private:
  struct Held {
    double release_s;
    SensorMessage message;
  };
  struct Active {
    Fault fault;
    std::mt19937_64 rng;                  // its own stream of the run seed
    uint64_t stream_seed = 0;             // that stream's seed (keyed per-frame draws)
    FaultFrameTally tally;                // what its frames showed
    std::optional<SensorMessage> frozen;  // stuck: the sample repeated
    cv::Mat frozen_whole;                 // stuck camera: the frame repeated
    double last_kept_s = -1e300;          // slow: capture time of the last sample kept
    std::deque<Held> held;                // delayed: messages held back
    bool release_pending = false;         // gripper late: a release waits
    bool released = false;                // gripper: its release has happened
  };
  // the fault's effect on one message; false: dropped or held
  bool Apply(Active* a, double now_s, SensorMessage* m);
  // whether distractor fault `a` is drawn in the frame of `now_s` (inside its window)
  static bool DistractorDrawn(const Active& a, double now_s);
  // counts one capture of distractor fault `a` and whether its detection is on the distractor
  static void TallyDistractorFrame(Active* a, double now_s, const SystemState& truth,
                                   const Params& world_params,
                                   const std::optional<PayloadDetection>& detection);
  // where distractor fault `a` is at `now_s` (m, world frame)
  static Eigen::Vector3d DistractorPosition_W(const Fault& f, double now_s);

  uint64_t run_seed_;
  std::vector<Active> faults_;
  std::vector<SensorMessage> incoming_;  // reused by FilterDelivered
};

}  // namespace hpa::sim
