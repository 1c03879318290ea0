// World: the MuJoCo model and data, the lockstep physics step, motors, state and the IMU,
// rate-gyro and VIO sample streams.

#include "hpa/sim/world.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>

#include "hpa/models/input_error.h"
#include "hpa/models/rotor_model.h"
#include "hpa/models/seed_streams.h"
#include "hpa/sim/camera_image_model.h"
#include "offscreen_renderer.h"
#include "world_detail.h"

namespace hpa::sim {

namespace {

// MuJoCo reports warnings through one global callback; we collect them per thread so a load or a
// step can turn them into an error message instead of a line on stderr.
thread_local std::string t_mujoco_warnings;

void CollectWarning(const char* message) {
  if (!t_mujoco_warnings.empty()) t_mujoco_warnings += "; ";
  t_mujoco_warnings += message;
}

int RequireId(const mjModel* m, const std::string& file, mjtObj type, const char* name,
              const char* what) {
  const int id = mj_name2id(m, type, name);
  if (id < 0)
    throw InputError(file, name, std::string("the scene needs a ") + what + " named " + name);
  return id;
}

const char* kRotorActuatorNames[4] = {"rotor0", "rotor1", "rotor2", "rotor3"};
const char* kRotorDiscNames[4] = {"rotor0_disc", "rotor1_disc", "rotor2_disc", "rotor3_disc"};

// The IMU noise the world simulates: the profile's IMU part when it has one.
SensorNoiseConfig ImuNoise(const WorldConfig& config) {
  SensorNoiseConfig noise = config.noise;
  if (config.profile.imu.enabled) {
    noise.gyro_noise_density_radps_rthz = config.profile.imu.gyro_noise_density_radps_rthz;
    noise.accel_noise_density_mps2_rthz = config.profile.imu.accel_noise_density_mps2_rthz;
  }
  return noise;
}

}  // namespace

void InstallWarningHandler() {
  static std::once_flag once;
  std::call_once(once, [] { mju_user_warning = CollectWarning; });
}

std::string TakeWarnings() {
  std::string w;
  w.swap(t_mujoco_warnings);
  return w;
}

World::World(const WorldConfig& config)
    : config_(config),
      world_params_(config.params),
      rng_(config.seed),
      imu_(ImuNoise(config), 1.0 / config.rates.imu.rate_hz, &rng_),
      vio_(config.noise, config.rates.vio.latency_s, &rng_),
      sensor_clock_(config.rates.physics_hz),
      vio_loop_(sensor_clock_.AddLoop("vio", config.rates.vio.rate_hz, TickRounding::kAtOrAfter)) {
  CheckRates();
  InstallWarningHandler();
  LoadScene();
  ResolveIds();
  // the world's own parameters: flight params, the profile's mismatch draw, then the scenario's
  // explicit overrides (which win over the draw)
  DrawMismatch();
  ApplyOverrides();
  data_ = mj_makeData(model_);
  ApplyWorldParams();
  if (config_.randomize_appearance) RandomizeAppearance();
  renderer_ = std::make_unique<OffscreenRenderer>(model_, config_.gl_backend);

  // start hovering 1 m up, payload hanging
  SystemState initial;
  initial.p_WQ_W = Eigen::Vector3d(0, 0, 1.0);
  initial.p_WL_W = initial.p_WQ_W - Eigen::Vector3d(0, 0, world_params_.cable_length_m);
  Reset(initial);
}

std::vector<SensorDeclaration> SensorDeclarations(const WorldConfig& config) {
  const RateTable& r = config.rates;
  const SensorNoiseConfig noise = ImuNoise(config);
  const auto text = [](double v) {
    std::ostringstream out;
    out << v;
    return out.str();
  };
  std::vector<SensorDeclaration> sensors = {
      {"imu", r.imu.rate_hz, r.imu.latency_s,
       "gyro " + text(noise.gyro_noise_density_radps_rthz) + " rad/s/sqrt(Hz), accel " +
           text(noise.accel_noise_density_mps2_rthz) + " m/s^2/sqrt(Hz), bias random walks",
       "RateTable::imu; noise: world profile imu"}};
  if (config.profile.rate_gyro.enabled) {
    sensors.push_back({"rate gyro (PX4's rate loop runs on it)", config.profile.rate_gyro.rate_hz,
                       0.0, "the IMU's gyro noise density and bias at this rate",
                       "rate_loop.rate_hz"});
  }
  sensors.push_back(
      {"vio", r.vio.rate_hz, r.vio.latency_s,
       "position " + text(config.noise.vio_position_sigma_m) + " m, attitude " +
           text(config.noise.vio_attitude_sigma_rad) + " rad, velocity " +
           text(config.noise.vio_velocity_sigma_mps) + " m/s per sample" +
           (config.profile.vio.enabled ? "; drift, dropouts and re-localisation" : ""),
       "RateTable::vio; drift: world profile vio"});
  sensors.push_back({"payload camera", r.camera.rate_hz, r.camera.latency_s,
                     "rendered: the camera image model; analytic: the detector's measured noise",
                     "RateTable::camera, estimation.camera_latency"});
  // every stream the world samples must be a whole number of physics steps apart
  for (const SensorDeclaration& s : sensors) {
    const double steps = r.physics_hz / s.rate_hz;
    if (!(steps >= 1.0) || std::abs(steps - std::round(steps)) > 1e-9) {
      if (s.name == "vio" || s.name == "payload camera") continue;  // sampled at or after a tick
      const bool imu = s.name == "imu";
      throw InputError("", imu ? "rates.imu" : "world.rate_loop.rate_hz",
                       imu ? "the IMU rate must divide the physics rate"
                           : "the rate must divide the physics rate");
    }
  }
  return sensors;
}

// The IMU must average a whole number of physics steps, and so must the rate loop's gyro.
void World::CheckRates() {
  const std::vector<SensorDeclaration> sensors = SensorDeclarations(config_);
  imu_steps_ = static_cast<int>(std::lround(config_.rates.physics_hz / sensors[0].rate_hz));
  // the rate loop's own gyro (PX4 rate loop): the IMU's part at the loop's rate
  if (config_.profile.rate_gyro.enabled) {
    const double steps = config_.rates.physics_hz / config_.profile.rate_gyro.rate_hz;
    rate_gyro_steps_ = static_cast<int>(std::lround(steps));
    // discrete white noise of the same density at this rate: sigma = density / sqrt(period)
    rate_gyro_sigma_radps_ = ImuNoise(config_).gyro_noise_density_radps_rthz /
                             std::sqrt(1.0 / config_.profile.rate_gyro.rate_hz);
  }
}

// Loads the MJCF; any load error or warning is bad input naming the file.
void World::LoadScene() {
  const std::string& file = config_.scene_path;

  if (!std::ifstream(file).good()) throw InputError(file, "", "cannot open the MJCF scene file");
  TakeWarnings();
  char error[1024] = "";
  model_ = mj_loadXML(file.c_str(), nullptr, error, sizeof(error));
  if (model_ == nullptr) throw InputError(file, "", std::string("MuJoCo cannot load it: ") + error);
  const std::string load_warnings = TakeWarnings();
  if (!load_warnings.empty() || error[0] != '\0') {
    mj_deleteModel(model_);
    throw InputError(file, "", "MuJoCo warning while loading: " + load_warnings + error);
  }
  if (std::abs(model_->opt.timestep - kPhysicsDt_s) > 1e-12 ||
      std::abs(config_.rates.physics_hz * kPhysicsDt_s - 1.0) > 1e-12) {
    mj_deleteModel(model_);
    throw InputError(file, "option.timestep", "must be 0.001 s (World::kPhysicsDt_s)");
  }
}

// Finds the named elements the world drives (bad input naming the first one missing).
void World::ResolveIds() {
  const std::string& file = config_.scene_path;
  try {
    ids_.quad_body = RequireId(model_, file, mjOBJ_BODY, "quadrotor", "body");
    ids_.payload_body = RequireId(model_, file, mjOBJ_BODY, "payload", "body");
    ids_.gripper_body = RequireId(model_, file, mjOBJ_BODY, "gripper", "mocap body");
    ids_.gripper_mocap = model_->body_mocapid[ids_.gripper_body];
    if (ids_.gripper_mocap < 0) throw InputError(file, "gripper", "must be a mocap body");
    ids_.gripper_weld = RequireId(model_, file, mjOBJ_EQUALITY, "gripper_weld", "weld");
    const int quad_jnt = RequireId(model_, file, mjOBJ_JOINT, "quadrotor_joint", "free joint");
    const int payload_jnt = RequireId(model_, file, mjOBJ_JOINT, "payload_joint", "free joint");
    if (model_->jnt_type[quad_jnt] != mjJNT_FREE || model_->jnt_type[payload_jnt] != mjJNT_FREE) {
      throw InputError(file, "quadrotor_joint", "quadrotor and payload joints must be free joints");
    }
    ids_.quad_jnt_qpos = model_->jnt_qposadr[quad_jnt];
    ids_.quad_jnt_dof = model_->jnt_dofadr[quad_jnt];
    ids_.payload_jnt_qpos = model_->jnt_qposadr[payload_jnt];
    ids_.payload_jnt_dof = model_->jnt_dofadr[payload_jnt];
    ids_.cable_tendon = RequireId(model_, file, mjOBJ_TENDON, "cable", "tendon");
    const int sensor = RequireId(model_, file, mjOBJ_SENSOR, "cable_tension", "sensor");
    ids_.tension_sensor_adr = model_->sensor_adr[sensor];
    ids_.payload_camera = RequireId(model_, file, mjOBJ_CAMERA, "payload_camera", "camera");
    ids_.chase_camera = RequireId(model_, file, mjOBJ_CAMERA, "chase", "camera");
    for (int i = 0; i < 4; ++i) {
      ids_.rotor_actuator[i] =
          RequireId(model_, file, mjOBJ_ACTUATOR, kRotorActuatorNames[i], "actuator");
      ids_.rotor_disc_geom[i] =
          RequireId(model_, file, mjOBJ_GEOM, kRotorDiscNames[i], "rotor disk geom");
    }
    ids_.payload_geom = RequireId(model_, file, mjOBJ_GEOM, "payload_sphere", "geom");
    ids_.quad_box_geom = RequireId(model_, file, mjOBJ_GEOM, "quadrotor_box", "geom");
    ids_.ground_geom = RequireId(model_, file, mjOBJ_GEOM, "ground", "geom");
    ids_.gripper_geom = mj_name2id(model_, mjOBJ_GEOM, "gripper_visual");
  } catch (...) {
    mj_deleteModel(model_);
    throw;
  }
}

// The scenario's explicit world overrides (they win over the mismatch draw).
void World::ApplyOverrides() {
  if (config_.overrides.payload_mass_kg) {
    if (!(*config_.overrides.payload_mass_kg > 0)) {
      mj_deleteModel(model_);
      throw InputError("", "world.payload_mass", "must be positive");
    }
    world_params_.payload_mass_kg = *config_.overrides.payload_mass_kg;
  }
  if (config_.overrides.cable_length_m) {
    if (!(*config_.overrides.cable_length_m > 0)) {
      mj_deleteModel(model_);
      throw InputError("", "world.cable_length", "must be positive");
    }
    world_params_.cable_length_m = *config_.overrides.cable_length_m;
  }
}

World::~World() {
  renderer_.reset();
  if (subframe_data_ != nullptr) mj_deleteData(subframe_data_);
  if (data_ != nullptr) mj_deleteData(data_);
  if (model_ != nullptr) mj_deleteModel(model_);
}

void World::Reset(const SystemState& initial) {
  mj_resetData(model_, data_);
  t0_s_ = initial.time_s;
  step_ = 0;
  data_->time = t0_s_;
  warning_count_.assign(mjNWARNING, 0);

  // disturbances, gripper, sensors, crash flag
  forces_.clear();
  gripper_moving_ = false;
  model_->eq_active[ids_.gripper_weld] = 0;
  rng_.seed(config_.seed);
  imu_.ResetBias();
  vio_.SetDrift(config_.profile.vio, DeriveSeed(config_.seed, SeedStream::kVioDrift));
  imu_queue_.clear();
  wind_rng_.seed(DeriveSeed(config_.seed, SeedStream::kWind));
  gust_W_mps_.setZero();
  event_wind_W_mps_.setZero();
  event_wind_end_step_ = 0;
  if (config_.profile.wind.gust_sigma_mps > 0.0) {
    // the gust starts from its stationary distribution
    std::normal_distribution<double> unit(0.0, 1.0);
    const WindProfile& wind = config_.profile.wind;
    for (int i = 0; i < 3; ++i) {
      gust_W_mps_(i) =
          wind.gust_sigma_mps * (i == 2 ? wind.gust_vertical_sigma_ratio : 1.0) * unit(wind_rng_);
    }
  }
  imu_sum_w_B_radps_.setZero();
  imu_sum_specific_force_B_mps2_.setZero();
  imu_sum_count_ = 0;
  rate_gyro_rng_.seed(DeriveSeed(config_.seed, SeedStream::kRateGyro));
  rate_gyro_sum_radps_.setZero();
  rate_gyro_sum_count_ = 0;
  rate_gyro_.reset();
  sensor_clock_ = LockstepClock(config_.rates.physics_hz);
  vio_loop_ = sensor_clock_.AddLoop("vio", config_.rates.vio.rate_hz, TickRounding::kAtOrAfter);
  crash_ = CrashStatus{};
  contact_counts_ = ContactCounts{};
  for (bool& t : touching_) t = false;

  // motors at hover speed of the simulated system
  const double w_hover = world_params_.HoverMotorSpeedRadps();
  SetState(initial.ToVector(), InputVector::Constant(w_hover));
  payload_quad_min_distance_m_ = PayloadQuadDistance();
  gripper_solid_ = false;
  gripper_used_ = false;
  UpdateGripperContact();
}

void World::SetState(const StateVector& x, const InputVector& motor_speed_radps) {
  if (!x.allFinite() || !motor_speed_radps.allFinite()) {
    throw std::invalid_argument("World::SetState: non-finite state or motor speed");
  }
  using I = StateIndex;
  mjtNum* qpos = data_->qpos;
  mjtNum* qvel = data_->qvel;
  const Eigen::Vector4d q = x.segment<4>(I::kQuat).normalized();
  for (int i = 0; i < 3; ++i) {
    qpos[ids_.quad_jnt_qpos + i] = x(I::kQuadPos + i);
    qpos[ids_.payload_jnt_qpos + i] = x(I::kPayloadPos + i);
    qvel[ids_.quad_jnt_dof + i] = x(I::kQuadVel + i);       // world frame
    qvel[ids_.quad_jnt_dof + 3 + i] = x(I::kBodyRate + i);  // body frame (free joint)
    qvel[ids_.payload_jnt_dof + i] = x(I::kPayloadVel + i);
    qvel[ids_.payload_jnt_dof + 3 + i] = 0.0;
  }
  for (int i = 0; i < 4; ++i) {
    qpos[ids_.quad_jnt_qpos + 3 + i] = q(i);
    qpos[ids_.payload_jnt_qpos + 3 + i] = (i == 0) ? 1.0 : 0.0;
  }
  motor_speed_radps_ = motor_speed_radps.cwiseMax(world_params_.motor_speed_min_radps)
                           .cwiseMin(world_params_.motor_speed_max_radps);
  motor_command_radps_ = motor_speed_radps_;
  WriteMotorControls();
  UpdateGripper();
  mj_forward(model_, data_);
  CheckWarnings();
}

void World::SetMotorSpeedCommand(const InputVector& w_cmd_radps) {
  if (!w_cmd_radps.allFinite()) {
    throw std::invalid_argument("World::SetMotorSpeedCommand: non-finite motor speed command");
  }
  motor_command_radps_ = w_cmd_radps.cwiseMax(world_params_.motor_speed_min_radps)
                             .cwiseMin(world_params_.motor_speed_max_radps);
}

void World::WriteMotorControls() {
  for (int i = 0; i < 4; ++i) {
    const double w = motor_speed_radps_(i);
    data_->ctrl[ids_.rotor_actuator[i]] =
        world_params_.k_f_N_per_radps2 * rotor_kf_factor_(i) * w * w;
  }
}

void World::Step() {
  // state at t_k is current (mj_forward / mj_step1 ran): sample what the sensors need from it
  sensor_clock_.BeginTick();  // the clock's tick is step_
  const bool vio_due = sensor_clock_.Fires(vio_loop_);
  const SystemState before = GetTruth().state;

  // first-order motor lag, exact for the 1 ms step; thrust to the actuators
  const double alpha = 1.0 - std::exp(-kPhysicsDt_s / world_params_.motor_time_constant_s);
  // (with battery sag the speed a command reaches falls with the pack voltage)
  const InputVector target_radps = config_.profile.actuation.enabled
                                       ? InputVector(motor_command_radps_ * BatterySpeedFactor())
                                       : motor_command_radps_;
  motor_speed_radps_ += alpha * (target_radps - motor_speed_radps_);
  WriteMotorControls();
  ApplyDisturbances();

  // dynamics at t_k and integration to t_{k+1}, then kinematics at t_{k+1}
  mj_step2(model_, data_);
  ++step_;
  UpdateGripper();
  mj_step1(model_, data_);
  CheckWarnings();

  // sensors, stamped with t_k (qacc from mj_step2 is the acceleration at t_k)
  // The IMU averages over its 2 ms period (a real IMU's internal high-rate sampling and
  // decimation filter): a point sample every other step would alias the 2 ms tension spike of a
  // re-taut into a velocity error of either twice or none of the true impulse.
  const double t_k = t0_s_ + (step_ - 1) * kPhysicsDt_s;
  imu_sum_w_B_radps_ += before.w_B;
  imu_sum_specific_force_B_mps2_ += QuadSpecificForce_B(before.q_WB);
  if (++imu_sum_count_ == imu_steps_) {
    const double interval_start_s = t_k - kPhysicsDt_s;
    imu_queue_.push_back(imu_.Measure(interval_start_s, imu_sum_w_B_radps_ / imu_sum_count_,
                                      imu_sum_specific_force_B_mps2_ / imu_sum_count_));
    imu_sum_w_B_radps_.setZero();
    imu_sum_specific_force_B_mps2_.setZero();
    imu_sum_count_ = 0;
    constexpr size_t kMaxQueued = 1000;  // 2 s of samples if the caller never takes them
    if (imu_queue_.size() > kMaxQueued) imu_queue_.pop_front();
  }
  if (rate_gyro_steps_ > 0) {
    // the rate loop's gyro: the same averaging over its own period, the IMU's current bias
    rate_gyro_sum_radps_ += before.w_B;
    if (++rate_gyro_sum_count_ == rate_gyro_steps_) {
      std::normal_distribution<double> unit(0.0, 1.0);
      GyroSample g;
      g.time_s = t_k - (rate_gyro_steps_ - 1) * kPhysicsDt_s;
      g.gyro_B_radps = rate_gyro_sum_radps_ / rate_gyro_steps_ + imu_.gyro_bias_B_radps();
      for (int i = 0; i < 3; ++i)
        g.gyro_B_radps(i) += rate_gyro_sigma_radps_ * unit(rate_gyro_rng_);
      rate_gyro_ = g;
      rate_gyro_sum_radps_.setZero();
      rate_gyro_sum_count_ = 0;
    }
  }
  if (vio_due) vio_.Capture(t_k, before.p_WQ_W, before.q_WB, before.v_WQ_W);
  sensor_clock_.Advance();
  UpdateContacts();
  UpdateGripperContact();
  CheckCrash();
}

Eigen::Vector3d World::QuadSpecificForce_B(const Eigen::Quaterniond& q_WB) const {
  const Eigen::Vector3d a_W(data_->qacc[ids_.quad_jnt_dof], data_->qacc[ids_.quad_jnt_dof + 1],
                            data_->qacc[ids_.quad_jnt_dof + 2]);
  const Eigen::Vector3d g_W(0, 0, world_params_.gravity_mps2);
  return q_WB.normalized().toRotationMatrix().transpose() * (a_W + g_W);
}

double World::time_s() const { return t0_s_ + step_ * kPhysicsDt_s; }

Truth World::GetTruth() const {
  Truth t;
  const mjtNum* qpos = data_->qpos;
  const mjtNum* qvel = data_->qvel;
  SystemState& s = t.state;
  s.time_s = time_s();
  s.p_WQ_W = Eigen::Map<const Eigen::Vector3d>(qpos + ids_.quad_jnt_qpos);
  s.q_WB = Eigen::Quaterniond(qpos[ids_.quad_jnt_qpos + 3], qpos[ids_.quad_jnt_qpos + 4],
                              qpos[ids_.quad_jnt_qpos + 5], qpos[ids_.quad_jnt_qpos + 6]);
  s.v_WQ_W = Eigen::Map<const Eigen::Vector3d>(qvel + ids_.quad_jnt_dof);
  s.w_B = Eigen::Map<const Eigen::Vector3d>(qvel + ids_.quad_jnt_dof + 3);
  s.p_WL_W = Eigen::Map<const Eigen::Vector3d>(qpos + ids_.payload_jnt_qpos);
  s.v_WL_W = Eigen::Map<const Eigen::Vector3d>(qvel + ids_.payload_jnt_dof);
  t.cable_length_m = (s.p_WL_W - s.p_WQ_W).norm();
  t.cable_tension_N = data_->sensordata[ids_.tension_sensor_adr];
  s.mode = t.cable_length_m >= world_params_.cable_length_m - kTautLengthTolerance_m
               ? CableMode::kTaut
               : CableMode::kSlack;
  s.payload_visible = true;
  t.motor_speed_radps = motor_speed_radps_;
  return t;
}

std::optional<ImuSample> World::TakeImu() {
  if (imu_queue_.empty()) return std::nullopt;
  ImuSample s = imu_queue_.front();
  imu_queue_.pop_front();
  return s;
}

std::optional<GyroSample> World::TakeRateGyro() {
  std::optional<GyroSample> g = rate_gyro_;
  rate_gyro_.reset();
  return g;
}

std::optional<VioSample> World::TakeVio() { return vio_.Take(time_s()); }

}  // namespace hpa::sim
