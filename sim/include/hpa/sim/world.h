#pragma once
// The simulated world (docs/design.md): MuJoCo physics of the quadrotor, the
// cable (a length-limited tendon) and the payload at 1 kHz, first-order motors, IMU and VIO
// models, disturbances, the gripper, crash detection and the rendered cameras.
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
#include "hpa/sim/faults.h"
#include "hpa/sim/gl_backend.h"
#include "hpa/sim/payload_camera.h"
#include "hpa/sim/sensor_models.h"
#include "hpa/sim/sensors.h"
#include "hpa/sim/wind.h"
#include "hpa/sim/world_profile.h"

// MuJoCo's model and data, only pointed to here (sim/src includes MuJoCo)
struct mjModel_;
struct mjData_;

namespace hpa::sim {

class OffscreenRenderer;
class CameraImageModel;

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

/// Contact episodes since Reset (a pair counts once each time it starts touching).
struct ContactCounts {
  int payload_body = 0;     // payload against the quadrotor's body box
  int payload_rotor = 0;    // payload against a rotor disk (a crash: rotor_strike)
  int payload_ground = 0;   // payload against the ground
  int quad_ground = 0;      // quadrotor against the ground (a crash)
  int payload_gripper = 0;  // payload against the gripper rod while not held (flight contact)
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

/// Wall time of one payload-camera frame, by stage.
struct CameraFrameTiming {
  double render_ms = 0.0;       // scene update, rasterisation, pixel read-out (all sub-frames)
  double image_model_ms = 0.0;  // motion blur, distortion, PSF, noise
};

/// Body selector for disturbances.
enum class Body { kQuadrotor, kPayload };

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

  /// Renders one payload-camera frame of a world of `config` and keeps its GL context, with the
  /// shaders llvmpipe compiled for it, for the process's next renderer of the same size: a
  /// process that forks workers calls it first so that each worker's first frame skips context
  /// creation and shader compilation. OSMesa only, and only where llvmpipe rasterises on the
  /// calling thread (LP_NUM_THREADS unset, which this sets to 0, or 0; and no context made in
  /// the process before): its worker threads do not survive fork. Returns whether the context
  /// was kept; same pixels either way.
  static bool PrewarmRendererForFork(const WorldConfig& config);

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
  const std::vector<std::unique_ptr<Sensor>>& sensors() const { return sensors_; }
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
  /// The wind: its declaration, gust and events.
  const WindModel& wind() const { return *wind_; }
  /// Captures the sensors that read the world at the start of a tick, before its step (the state
  /// and events the flight stack's tick sees): the gripper's switch, and the payload camera's
  /// frame when one is due, read out through `readout` (rendered frames only; not owned). Each
  /// is queued for delivery after its latency like every sensor's message (TakeDelivered).
  /// The camera's capture, if it fired.
  std::optional<CameraCapture> CaptureTickStart(CameraReadout* readout);

  /// Applies impulse_W_Ns (N s, world frame) at the body's centre of mass as a constant force
  /// over duration_s (rounded to whole steps, at least one).
  void ApplyImpulse(Body body, const Eigen::Vector3d& impulse_W_Ns, double duration_s = 0.01);
  /// Adds dv_W_mps (m/s, world frame) to the body's linear velocity at once (its free joint's
  /// qvel; a taut cable or a held gripper then acts on the new velocity from the next step).
  void AddVelocity(Body body, const Eigen::Vector3d& dv_W_mps);
  /// Constant force (N, world frame) on the quadrotor's centre of mass for duration_s.
  void SetWind(const Eigen::Vector3d& force_W_N, double duration_s);
  /// Adds a wind velocity (m/s, world frame) to the profile's wind for duration_s; it acts
  /// through the profile's drag (none in a world without aerodynamics).
  void SetWindVelocity(const Eigen::Vector3d& velocity_W_mps, double duration_s);

  /// The world's faults (faults.h): scenario fault events inject into it; every fault's effect
  /// lives there, so a new fault adds no World method.
  Faults& faults() { return faults_; }

  /// Welds the payload to the gripper where it is now (moves the mocap body onto it first).
  void GripperGrab();
  /// Moves the gripper (and a held payload) to to_W_m along a minimum-jerk path over duration_s.
  void GripperMove(const Eigen::Vector3d& to_W_m, double duration_s);
  /// Lets the payload go.
  void GripperRelease();
  /// True while the gripper holds the payload.
  bool gripper_active() const;

  /// Latched: quad body contact with ground/obstacle, tilt > 90 deg, outside the arena
  /// (|x|, |y| <= kArenaHalfWidth_m, 0 <= z <= kArenaHeight_m), non-finite state.
  CrashStatus Crash() const;

  /// Payload camera frame, CV_8UC3 BGR, 1280x720, top row first (first call creates the GL
  /// context of config.gl_backend):   /// a single-sample pinhole render turned into the sensor's
  /// image by the profile's camera image model (CameraImageModel: motion blur, distortion, PSF,
  /// noise).
  cv::Mat RenderPayloadCamera();
  /// As above, into `bgr` (reallocated only when its size or type differs). A non-empty
  /// `region` computes only that part of the image, equal to the whole frame's there (the rest
  /// of `bgr` is left as it was): what a detector reading only a region needs.
  void RenderPayloadCamera(cv::Mat* bgr, const cv::Rect& region = cv::Rect());
  /// Wall time of the last payload frame's render and of its image model.
  const CameraFrameTiming& last_camera_timing() const { return camera_timing_; }
  /// Image motion (render pixels) of the payload's centre over one exposure now, and the
  /// region of the render the payload covers (for the fast motion-blur approximation).
  Eigen::Vector2d PayloadImageMotionPx(cv::Rect* region) const;
  /// Chase camera frame for videos, CV_8UC3 BGR, top row first (at most 1280x720).
  cv::Mat RenderChaseCamera(int width_px, int height_px);

  /// For tests: sets qpos/qvel exactly from x and the actual motor speeds (and the command) to
  /// motor_speed_radps, then recomputes kinematics; no lag transient follows.
  void SetState(const StateVector& x, const InputVector& motor_speed_radps);

  /// Parameters the world actually simulates (params with the profile's mismatch draw and the
  /// overrides applied).
  const Params& world_params() const { return world_params_; }

  /// Smallest surface-to-surface distance (m) between the payload sphere and the vehicle (body
  /// box and rotor disks) since Reset; negative: they overlapped by that much.
  double payload_quad_min_distance_m() const { return payload_quad_min_distance_m_; }
  /// Surface-to-surface distance (m) between the payload and the vehicle now.
  double PayloadQuadDistance() const;
  /// Contact episodes since Reset.
  const ContactCounts& contact_counts() const { return contact_counts_; }
  /// Thrust coefficient of each rotor relative to the world's k_f (actuation spread)  (4)
  const Eigen::Vector4d& rotor_thrust_factor() const { return rotor_kf_factor_; }
  /// Rotor speed reached per unit command now (battery sag; 1 with a full pack or no sag).
  double BatterySpeedFactor() const;
  /// Wind velocity at the vehicle now (m/s, world frame): steady part plus gust  (3)
  Eigen::Vector3d Wind_W_mps() const;
  /// Aerodynamic force on the quadrotor in the last step (N, world frame)  (3)
  const Eigen::Vector3d& aero_quad_W_N() const { return aero_quad_W_N_; }
  /// Aerodynamic force on the payload in the last step (N, world frame)  (3)
  const Eigen::Vector3d& aero_payload_W_N() const { return aero_payload_W_N_; }

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
  struct TimedForce {
    Body body;
    Eigen::Vector3d force_W_N;  // (3)
    int64_t end_step;           // applied while step < end_step
  };

  void LoadScene();
  void ResolveIds();
  void ApplyOverrides();
  void ApplyWorldParams();
  void ApplyContactSettings();
  void ApplyCameraPose(const Params& p);
  void WriteMotorControls();
  void UpdateGripper();
  void ApplyDisturbances();
  void UpdateSensors();
  void CheckCrash();
  void CheckWarnings();
  void DrawMismatch();
  void RandomizeAppearance();
  void ApplyAerodynamics();
  void UpdateContacts();
  void UpdateGripperContact();
  double PayloadGripperDistance() const;
  void LatchCrash(const std::string& reason);
  // specific force R^T (a + g e3) from qacc (time t_k) in the attitude q_WB of that same time
  Eigen::Vector3d QuadSpecificForce_B(const Eigen::Quaterniond& q_WB) const;

  WorldConfig config_;
  Params world_params_;
  friend struct WorldInternals;  // sim/src/world_internals.h: MuJoCo access for sim tests
  mjModel_* model_ = nullptr;
  mjData_* data_ = nullptr;
  Ids ids_{};
  double t0_s_ = 0.0;
  int64_t step_ = 0;
  std::vector<int> warning_count_;  // per MuJoCo warning kind (mjNWARNING)

  InputVector motor_speed_radps_ = InputVector::Zero();    // actual (4)
  InputVector motor_command_radps_ = InputVector::Zero();  // commanded, clamped (4)

  std::vector<TimedForce> forces_;

  // gripper motion: min-jerk from start to goal over [start_step, end_step]
  bool gripper_moving_ = false;
  Eigen::Vector3d gripper_from_W_m_ = Eigen::Vector3d::Zero();  // (3)
  Eigen::Vector3d gripper_to_W_m_ = Eigen::Vector3d::Zero();    // (3)
  int64_t gripper_start_step_ = 0;
  int64_t gripper_end_step_ = 0;

  std::mt19937_64 rng_;  // the IMU's and VIO's noise
  std::vector<std::unique_ptr<Sensor>> sensors_;
  std::vector<DelayLine<SensorMessage>> deliveries_;  // one per sensor, its declared latency
  std::vector<int> sensor_lines_;                     // each of sensors_'s place in deliveries_
  int imu_sensor_ = -1, rate_gyro_sensor_ = -1, vio_sensor_ = -1;  // their places in sensors_
  std::unique_ptr<GripperSensor> gripper_sensor_;
  std::unique_ptr<PayloadCameraSensor> camera_;
  int gripper_line_ = -1, camera_line_ = -1;  // their places in deliveries_ (after the sensors')

  Faults faults_;  // sensor and actuator faults (empty: every hook skipped)
  CrashStatus crash_;
  std::unique_ptr<OffscreenRenderer> renderer_;
  std::unique_ptr<CameraImageModel> camera_image_;  // created with the first payload frame
  std::future<void> camera_tables_;            // its shared tables, computed from construction on
  mjData_* subframe_data_ = nullptr;           // kinematics of exposure sub-frames
  cv::Mat pinhole_, subframe_, subframe_sum_;  // reused frame buffers
  CameraFrameTiming camera_timing_;

  // realism profile state
  Eigen::Vector4d rotor_kf_factor_ = Eigen::Vector4d::Ones();  // per-rotor k_f spread  (4)
  Eigen::Vector4d rotor_km_factor_ = Eigen::Vector4d::Ones();  // per-rotor k_m spread  (4)
  double payload_quad_min_distance_m_ = 0.0;
  ContactCounts contact_counts_;
  std::unique_ptr<WindModel> wind_;                             // mean wind, gust, wind events
  Eigen::Vector3d aero_quad_W_N_ = Eigen::Vector3d::Zero();     // last drag on the quad  (3)
  Eigen::Vector3d aero_payload_W_N_ = Eigen::Vector3d::Zero();  // last drag on the payload  (3)
  bool touching_[5] = {false, false, false, false, false};      // ContactCounts fields, last step
  bool gripper_solid_ = false;  // the gripper's rod collides (flight contact, not holding, clear)
  bool gripper_used_ = false;   // an event has grabbed with or moved the gripper in this run
};

}  // namespace hpa::sim
