#pragma once
// The simulated world of a team (docs/cooperative.md): N quadrotors on their own cables carrying
// one rigid-body payload, in MuJoCo (the scene of CooperativeSceneXml), at the single-vehicle
// world's 1 kHz. Each vehicle has the single vehicle's components: its first-order motors
// (vehicle.h), its faults (faults.h) and, when asked for, its onboard sensors (IMU, VIO, the rate
// gyro: sensor_suite.h); the world's disturbances (disturbances.h) push, drag and blow on every
// body. The team's motion-capture system reports every body's pose and velocity at its declared
// rate, latency and noise (RotorTM's experiments fly on one), and each vehicle has a simple rate
// gyro of its own. MuJoCo stays inside sim/src; flight code never sees it.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "hpa/models/cooperative_model.h"
#include "hpa/models/data_dir.h"
#include "hpa/models/state.h"
#include "hpa/sim/gl_backend.h"
#include "hpa/sim/team_renderer.h"
#include "hpa/sim/world.h"

namespace hpa::sim {

/// The team's motion-capture system: every body's pose and velocity, sampled at rate_hz and
/// delivered latency_s later with white noise of the given standard deviations.
struct MocapConfig {
  double rate_hz = 100.0;
  double latency_s = 0.01;
  double position_noise_m = 0.001;      // per axis
  double velocity_noise_mps = 0.01;     // per axis
  double attitude_noise_rad = 0.005;    // per axis, a small rotation applied to the true one
  double rate_gyro_noise_radps = 0.01;  // each vehicle's gyro, sampled every physics step
  double body_rate_noise_radps = 0.01;  // per axis, the body rate in a motion-capture reading
};

/// Everything a TeamWorld is built from.
struct TeamWorldConfig {
  CooperativeTeam team;                                   // payload and N vehicles
  std::string scene_path = DataPath("models/scene.xml");  // single-vehicle scene it is built from
  uint64_t seed = 1;  // the motion capture's generator; every other stream derived from it
  MocapConfig mocap;
  GlBackend gl_backend = GlBackend::kOsMesa;  // GL context of the video's cameras (renderer())
  SensorNoiseConfig noise;                    // each vehicle's IMU and VIO noise (as WorldConfig's)
  RateTable rates;  // physics (1 kHz), IMU and VIO rates and latencies (as WorldConfig's)
  // realism parts (default: all off, the ideal world), each on every vehicle: the onboard
  // sensors' (imu, vio, rate_gyro), the air's (aero, wind), the actuation's (rotor spread,
  // battery sag) and the model mismatch (each vehicle's parameters and cable, the payload's mass:
  // team() is the drawn team); the single vehicle's contacts and camera are not a team's
  WorldProfile profile;
  // each vehicle carries the single vehicle's IMU, VIO and rate gyro (off: none sampled)
  bool onboard_sensors = false;
};

/// One body's pose and velocity as the motion-capture system saw it.
struct BodyReading {
  int body = -1;                // -1: the payload; 0 .. N-1: that vehicle
  double capture_time_s = 0.0;  // when it was sampled (delivered latency_s later)
  Eigen::Vector3d p_W_m = Eigen::Vector3d::Zero();          // position, world (3)
  Eigen::Vector3d v_W_mps = Eigen::Vector3d::Zero();        // velocity, world (3)
  Eigen::Quaterniond q_W = Eigen::Quaterniond::Identity();  // attitude in world
  Eigen::Vector3d w_body_radps = Eigen::Vector3d::Zero();   // body rate, body frame (3)
};

/// Ground truth of a team now.
struct TeamTruth {
  double time_s = 0.0;
  Eigen::VectorXd x;                    // CooperativeStateIndex layout, 13 (N + 1)
  std::vector<double> cable_length_m;   // each vehicle's cable, |p_A_i - p_Q_i|  (N)
  std::vector<double> cable_tension_N;  // each cable's tendon limit force  (N)
                                        // (>= 0, a pull; the force of the last step, as Truth's)
  std::vector<CableMode> modes;         // taut iff the cable is within 1 mm of its length  (N)
  Eigen::VectorXd motor_speed_radps;    // actual rotor speeds, vehicle by vehicle  (4N)
};

/// The team's world, stepped by the team runner in lockstep with each vehicle's flight code.
class TeamWorld {
 public:
  /// Builds the MJCF of config.team from config.scene_path; throws hpa::InputError naming the
  /// scene for one that cannot be built or loaded, or a team that is empty or larger than 3.
  /// Also hpa::InputError naming the field ("team.vehicles[1].cable_length_m",
  /// "team.payload_mass_kg", "mocap.rate_hz", ...) for a non-positive length, mass, inertia or
  /// rotor constant, a rate that is not a whole number of physics steps, or a negative latency or
  /// noise. The vehicles collide with each other and with the payload (contact pairs added to
  /// CooperativeSceneXml's scene), and with the ground. Starts Reset to the team's
  /// CooperativeModel::HangingState with the payload 1 m up.
  explicit TeamWorld(const TeamWorldConfig& config);
  ~TeamWorld();
  TeamWorld(const TeamWorld&) = delete;
  TeamWorld& operator=(const TeamWorld&) = delete;

  /// Number of vehicles N.
  int VehicleCount() const;
  /// Places every body at x0 (CooperativeStateIndex layout, velocities and rates as given),
  /// each vehicle's motors (and command) at the speed that holds its own weight and its cable's
  /// share of the payload's (slack cable: its own weight only), time = 0; clears the delivery
  /// queues, the faults, the pushes (the wind back to its start) and the crash flag, resets the
  /// onboard sensors and re-seeds every generator, so a Reset world replays the same noise.
  /// A cable is taut when its vehicle is within World::kTautLengthTolerance_m of its length
  /// from its attachment point; the taut cables' shares are the tensions along them that hold
  /// the payload's weight with no net moment about its centre (least squares, minimum norm).
  /// Takes the gyros' and the first motion capture's samples (t = 0). A state of the wrong size
  /// or with non-finite entries throws std::invalid_argument.
  void Reset(const Eigen::VectorXd& x0);
  /// Vehicle's new rotor speed command (rad/s), clamped to its motor bounds; non-finite entries
  /// throw std::invalid_argument, a vehicle outside 0 .. N-1 std::out_of_range.
  void SetMotorSpeedCommand(int vehicle, const InputVector& w_cmd_radps);
  /// A push as the single vehicle's World gives it (Disturbances::ApplyImpulse): a constant
  /// force impulse / duration on the body (-1: payload) over the duration's whole physics steps
  /// (at least one), from the next Step on. A body outside -1 .. N-1 throws std::out_of_range, a
  /// non-finite impulse or duration std::invalid_argument.
  void ApplyImpulse(int body, const Eigen::Vector3d& impulse_W_Ns, double duration_s);
  /// An instantaneous velocity change of the body (-1: payload), as a velocity_change event
  /// gives it. A body outside -1 .. N-1 throws std::out_of_range, a non-finite change
  /// std::invalid_argument.
  void AddVelocity(int body, const Eigen::Vector3d& dv_W_mps);
  /// Advances 1 ms: motors, disturbances, mj_step, sensors, crash check.
  void Step();
  /// Simulated time (s), a multiple of World::kPhysicsDt_s.
  double time_s() const;

  /// Ground truth now.
  TeamTruth GetTruth() const;
  /// Ground truth now into *truth, reusing its vectors' memory (no allocation once sized).
  void GetTruth(TeamTruth* truth) const;
  /// Every motion-capture reading whose latency has passed, in capture order (payload first,
  /// then vehicle 0, 1, ... within one capture).
  /// A capture is taken at Reset and after every Step that reaches a multiple of 1 / rate_hz,
  /// of the state at that time; it is delivered once time_s() >= capture + latency_s (1 ns
  /// rounding margin). The attitude noise is a rotation in the body frame: q_W = q_true *
  /// exp(n), n ~ N(0, attitude_noise_rad^2) per axis.
  std::vector<BodyReading> TakeDelivered();
  /// TakeDelivered into *readings (cleared first, its memory kept).
  void TakeDelivered(std::vector<BodyReading>* readings);
  /// Vehicle's rate-gyro sample of this step (body frame, rad/s, with noise).
  /// The true body rate at time_s() plus N(0, rate_gyro_noise_radps^2) per axis, drawn at Reset
  /// and after every Step. A vehicle outside 0 .. N-1 throws std::out_of_range.
  Eigen::Vector3d GyroSample_B(int vehicle) const;

  /// Vehicle's faults (faults.h), as the single World's faults(): a scenario's fault event on a
  /// vehicle injects into them, its motors read them (a motor's loss or failure) and its onboard
  /// sensors' delivery goes through them (an imu or vio fault); cleared by Reset. A vehicle
  /// outside 0 .. N-1 throws std::out_of_range.
  Faults& faults(int vehicle);

  /// Whether each vehicle carries onboard sensors (config.onboard_sensors).
  bool onboard_sensors() const;
  /// Vehicle's onboard sensors, the single vehicle's MakeSensors list for its params and the
  /// team's noise, rates and profile, its generator seeded per vehicle
  /// (DeriveVehicleSeed(seed, SeedStream::kOnboardSensors, vehicle)); empty without onboard
  /// sensors. Sampled after every Step on the vehicle's true state at the step's start (its
  /// attachment point as the payload) and the specific force of that step. A vehicle outside
  /// 0 .. N-1 throws std::out_of_range.
  const std::vector<std::unique_ptr<Sensor>>& sensors(int vehicle) const;
  /// Vehicle's onboard sensor messages whose latency has passed, sensor by sensor in capture
  /// order, through its faults (as World::TakeDelivered), into `out` (cleared first, its memory
  /// kept). A vehicle outside 0 .. N-1 throws std::out_of_range.
  void TakeDelivered(int vehicle, std::vector<SensorMessage>* out);

  /// Forces, impulses, velocity changes, wind and drag on the team's bodies (disturbances.h;
  /// BodyRef(-1) is the payload, BodyRef(i) vehicle i). With the profile's aero part each
  /// vehicle feels the single quadrotor's drag (its own params' box) and the payload a sphere's.
  Disturbances& disturbances();

  /// Latched: a vehicle's contact with the ground, the payload or another vehicle (the latter
  /// named "vehicle 0 and vehicle 1 collide"), a vehicle's tilt > 90 deg, any body leaving the
  /// arena (kArenaHalfWidth_m, kArenaHeight_m), non-finite state. The reason names the vehicle.
  /// Reasons: "vehicle 0 and vehicle 1 collide", "vehicle 1 contact with ground", "vehicle 1
  /// contact with payload", "vehicle 2 tilt > 90 deg", "vehicle 0 left the 20x20x10 m arena",
  /// "payload left the 20x20x10 m arena", "payload non-finite state". The payload on the ground
  /// is not a crash. Checked after every Step (not at Reset).
  CrashStatus Crash() const;
  /// Smallest distance between two vehicles' centres now (m; infinity for one vehicle).
  double MinVehicleSeparation_m() const;

  /// The team the world simulates: config.team with the profile's mismatch draw (the flight
  /// code's team is config.team).
  const CooperativeTeam& team() const;

  /// The team's video cameras (team_renderer.h), made on first use so a run that never renders
  /// pays nothing; they only read the world's state.
  TeamRenderer& renderer();

 private:
  friend class TeamRenderer;
  // what the renderer reads: the physics model and data (read only) and the scene's MJCF text
  const mjModel_* model() const;
  const mjData_* data() const;
  const std::string& scene_xml() const;
  GlBackend gl_backend() const;

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hpa::sim
