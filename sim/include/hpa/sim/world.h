#pragma once
// The simulated world (docs/design.md): MuJoCo physics of the quadrotor, the cable (a
// length-limited tendon) and the payload at 1 kHz, its sensors' delivery and crash detection, and
// the components it owns and steps, each in its own header: the vehicle's motors (vehicle.h), the
// gripper (gripper.h), disturbances and wind (disturbances.h), contacts (contacts.h), the rendered
// cameras (renderer.h) and faults (faults.h). An event or a fault acts on the component it needs.
// MuJoCo stays inside sim/src (this header only points to its model and data); flight code never
// sees it.

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <future>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "hpa/models/data_dir.h"
#include "hpa/models/params.h"
#include "hpa/models/sensor_types.h"
#include "hpa/models/state.h"
#include "hpa/sim/contacts.h"
#include "hpa/sim/disturbances.h"
#include "hpa/sim/faults.h"
#include "hpa/sim/gl_backend.h"
#include "hpa/sim/gripper.h"
#include "hpa/sim/payload_camera.h"
#include "hpa/sim/renderer.h"
#include "hpa/sim/sensor_models.h"
#include "hpa/sim/sensor_suite.h"
#include "hpa/sim/sensors.h"
#include "hpa/sim/vehicle.h"
#include "hpa/sim/wind.h"
#include "hpa/sim/world_profile.h"

// MuJoCo's model and data, only pointed to here (sim/src includes MuJoCo)
struct mjModel_;
struct mjData_;

namespace hpa::sim {

/// Perturbations of the simulated world only (the flight code keeps Params): model mismatch.
struct WorldOverrides {
  std::optional<double> payload_mass_kg;  // payload mass; inertia scaled with it
  std::optional<double> cable_length_m;   // cable (tendon range) length
};

/// Everything a World is built from.
struct WorldConfig {
  Params params;             // flight parameters (params.yaml)
  WorldOverrides overrides;  // perturb the WORLD only (mass, cable length): model mismatch
  std::string scene_path = DataPath("models/scene.xml");  // MJCF file
  uint64_t seed = 1;                                      // the one generator for all sensor noise
  SensorNoiseConfig noise;                                // IMU and VIO noise
  RateTable rates;                                        // physics, IMU and VIO rates, VIO latency
  WorldProfile profile;               // realism parts (default: all off, the ideal world)
  PayloadCameraConfig camera;         // what the payload camera produces (payload_camera.h)
  bool randomize_appearance = false;  // floor shade, texture scale and lights drawn from the seed
  // GL context of the rendered cameras (one back end per process: sim/src/gl_context.h)
  GlBackend gl_backend = GlBackend::kOsMesa;
};

/// Ground truth at the current time.
struct Truth {
  SystemState state;             // true state; mode = kTaut iff cable length >= l - 1 mm
  double cable_tension_N = 0.0;  // tendon limit force (tendonlimitfrc sensor)
  double cable_length_m = 0.0;   // tendon length |x_L - x_Q|
  InputVector motor_speed_radps = InputVector::Zero();  // actual (lagged) rotor speeds  (4)
};

/// Latched crash flag (docs/design.md section 8).
struct CrashStatus {
  bool crashed = false;
  double time_s = 0;   // time of the first crash condition
  std::string reason;  // which condition ("ground contact", "tilt > 90 deg", ...)
};

/// The arena the vehicle flies in: |x|, |y| <= kArenaHalfWidth_m and 0 <= z <= kArenaHeight_m
/// (a 20 x 20 x 10 m hall); leaving it is a crash, and a scenario must fit inside it.
constexpr double kArenaHalfWidth_m = 10.0;
constexpr double kArenaHeight_m = 10.0;

/// The simulated world the scenario runner steps in lockstep with the flight code.
class World {
 public:
  /// Loads the MJCF, applies params and overrides; throws hpa::InputError naming the file for a
  /// bad or missing MJCF (or one without the named bodies, tendon, actuators and cameras).
  explicit World(const WorldConfig& config);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  static constexpr double kPhysicsDt_s = 0.001;  // MuJoCo timestep (s): RateTable::physics_hz
  /// Truth mode threshold: taut when the cable length >= l - kTautLengthTolerance_m.
  static constexpr double kTautLengthTolerance_m = 0.001;
  /// Flight profile: the vehicle's contacts start this far before the surfaces meet, so a payload
  /// arriving at up to 30 m/s (3 cm per step; the impulse sweep's top, 2.5 N s on 0.1 kg, is
  /// 25 m/s) is stopped before it overlaps the vehicle. A payload within it of a rotor disk has
  /// struck the rotor.
  static constexpr double kContactMargin_m = 0.03;

  /// Places quad + payload at `initial` (velocities and body rate as given, zero by default),
  /// motors at hover speed (also the command), time = initial.time_s; clears disturbances,
  /// gripper, sensor queues, biases and the crash flag; re-seeds the noise generator with
  /// config.seed, so a Reset world replays the same noise.
  void Reset(const SystemState& initial);
  /// New rotor speed command (rad/s), clamped to the motor bounds; the motors follow it with
  /// the first-order lag motor_time_constant_s. Non-finite entries throw std::invalid_argument.
  void SetMotorSpeedCommand(const InputVector& w_cmd_radps);
  /// Advances 1 ms: motors, disturbances, gripper, mj_step, sensors, crash check.
  void Step();
  /// Simulated time (s), exact multiple of kPhysicsDt_s from the Reset time.
  double time_s() const;

  /// Ground truth now.
  Truth GetTruth() const;
  /// The world's sensors, in the order it samples them (each declares its rate, latency and
  /// noise).
  const std::vector<std::unique_ptr<Sensor>>& sensors() const { return sensors_.sensors(); }
  /// Every sensor message whose latency has passed, sensor by sensor in the list's order, each
  /// sensor's in capture order (what the flight computer receives after this step).
  std::vector<SensorMessage> TakeDelivered();
  /// TakeDelivered into `out` (cleared first), reusing its memory: no allocation per step.
  void TakeDelivered(std::vector<SensorMessage>* out);
  /// Adds a sensor after those of MakeSensors (what one line in MakeSensors does, at run time):
  /// it is sampled after every step and delivered after its declared latency. Its rate-table row
  /// is the caller's to print.
  void AddSensor(std::unique_ptr<Sensor> sensor);
  /// Every message still in a delay line (the end of a run), line by line in capture order.
  std::vector<SensorMessage> TakeInFlight();
  /// The payload camera: its declaration and clock.
  const PayloadCameraSensor& payload_camera() const { return *camera_; }
  /// Captures the sensors that read the world at the start of a tick, before its step (the state
  /// and events the flight stack's tick sees): the gripper's switch, and the payload camera's
  /// frame when one is due. Each message is queued for delivery after its latency like every
  /// sensor's (TakeDelivered): the analytic camera's detection here; a rendered frame is the
  /// capture's exposure (`region` read first), which the flight stack reads out before the world
  /// steps, handing back what it made of it with QueueCameraMessage.
  /// The camera's capture, if it fired.
  std::optional<CameraCapture> CaptureTickStart(const cv::Rect& region = cv::Rect());
  /// Whether the payload camera captures a frame at this tick's CaptureTickStart.
  bool CameraFrameDue() const { return camera_->FrameDue(step_); }
  /// Queues the flight stack's reading of a rendered exposure (its detection, or the frames it
  /// receives) as the camera's message, for delivery after the camera's latency.
  void QueueCameraMessage(SensorMessage message);

  /// The world's faults (faults.h): scenario fault events inject into it; every fault's effect
  /// lives there, so a new fault adds no World method.
  Faults& faults() { return faults_; }

  /// Latched: quad body contact with ground/obstacle, tilt > 90 deg, outside the arena
  /// (|x|, |y| <= kArenaHalfWidth_m, 0 <= z <= kArenaHeight_m), non-finite state.
  CrashStatus Crash() const;

  /// For tests: sets qpos/qvel exactly from x and the actual motor speeds (and the command) to
  /// motor_speed_radps, then recomputes kinematics; no lag transient follows.
  void SetState(const StateVector& x, const InputVector& motor_speed_radps);

  /// Parameters the world actually simulates (params with the profile's mismatch draw and the
  /// overrides applied).
  const Params& world_params() const { return world_params_; }

  /// The vehicle's motors and rotors (vehicle.h): their spread, battery sag and speeds.
  const Vehicle& vehicle() const { return *vehicle_; }
  /// The gripper (gripper.h): grab, move and release events act on it.
  Gripper& gripper() { return *gripper_; }
  /// Forces, impulses, velocity changes and wind (disturbances.h): their events act on it.
  Disturbances& disturbances() { return *disturbances_; }
  /// Contact episodes and the payload's distance to the vehicle (contacts.h).
  const Contacts& contacts() const { return *contacts_; }
  /// The payload and chase cameras (renderer.h).
  Renderer& renderer() { return *renderer_; }

 private:
  struct Ids {
    int quad_body, payload_body, gripper_body, gripper_mocap, gripper_weld;
    int quad_jnt_qpos, quad_jnt_dof, payload_jnt_qpos, payload_jnt_dof;
    int cable_tendon, tension_sensor_adr, payload_camera, chase_camera;
    int rotor_actuator[4];
    int payload_geom, quad_box_geom, ground_geom;
    int gripper_geom;  // the gripper's rod (-1: the scene has none)
    int rotor_disc_geom[4];
  };

  void LoadScene();
  void BindDisturbances();
  void ResolveIds();
  void ApplyOverrides();
  void ApplyWorldParams();
  void ApplyContactSettings();
  void ApplyCameraPose(const Params& p);
  void CheckCrash();
  void CheckWarnings();
  void DrawMismatch();
  void LatchCrash(const std::string& reason);

  WorldConfig config_;
  Params world_params_;
  friend struct WorldInternals;  // sim/src/world_internals.h: MuJoCo access for sim tests
  // the renderer reaches the model, the data and the step through its world
  friend class Renderer;
  mjModel_* model_ = nullptr;
  mjData_* data_ = nullptr;
  Ids ids_{};
  double t0_s_ = 0.0;
  int64_t step_ = 0;
  std::vector<int> warning_count_;  // per MuJoCo warning kind (mjNWARNING)

  // the IMU, rate gyro and VIO with their noise generator, and every sensor's delay line
  SensorSuite sensors_;
  std::unique_ptr<GripperSensor> gripper_sensor_;
  std::unique_ptr<PayloadCameraSensor> camera_;
  int gripper_line_ = -1, camera_line_ = -1;  // their lines in sensors_ (after the sensors')

  Faults faults_;  // sensor and actuator faults (empty: every hook skipped)
  CrashStatus crash_;

  // the components, stepped by Step in its order
  std::optional<Vehicle> vehicle_;  // bound to the rotors once the model and data exist
  // the actuation spread drawn with the mismatch, before the vehicle is bound  (4 each)
  Eigen::Vector4d rotor_kf_draw_ = Eigen::Vector4d::Ones(),
                  rotor_km_draw_ = Eigen::Vector4d::Ones();
  std::optional<Gripper> gripper_;            // bound to the scene's hand once it is loaded
  std::optional<Disturbances> disturbances_;  // bound to the scene's bodies once it is loaded
  std::optional<Contacts> contacts_;          // bound to the scene's geometry once it is loaded
  std::unique_ptr<Renderer> renderer_;        // made once the model is loaded; released first
};

}  // namespace hpa::sim
