#include "hpa/sim/world.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

#include "hpa/models/input_error.h"
#include "hpa/models/rotor_model.h"
#include "hpa/sim/camera_image_model.h"
#include "offscreen_renderer.h"

namespace hpa::sim {
namespace {

// MuJoCo reports warnings through one global callback; we collect them per thread so a load or a
// step can turn them into an error message instead of a line on stderr.
thread_local std::string t_mujoco_warnings;

void CollectWarning(const char* message) {
  if (!t_mujoco_warnings.empty()) t_mujoco_warnings += "; ";
  t_mujoco_warnings += message;
}

void InstallWarningHandler() {
  static std::once_flag once;
  std::call_once(once, [] { mju_user_warning = CollectWarning; });
}

std::string TakeWarnings() {
  std::string w;
  w.swap(t_mujoco_warnings);
  return w;
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

// Signed distance (m) from point p to an axis-aligned box of half sizes h at the origin
// (negative inside: minus the depth to the nearest face).
double BoxSignedDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& h) {
  const Eigen::Vector3d q = p.cwiseAbs() - h;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

// Signed distance (m) from point p to a solid cylinder of radius r and half height h along z at
// the origin (negative inside).
double CylinderSignedDistance(const Eigen::Vector3d& p, double r, double h) {
  const Eigen::Vector2d q(p.head<2>().norm() - r, std::abs(p.z()) - h);
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

// The IMU noise the world simulates: the profile's IMU part when it has one.
SensorNoiseConfig ImuNoise(const WorldConfig& config) {
  SensorNoiseConfig noise = config.noise;
  if (config.profile.imu.enabled) {
    noise.gyro_noise_density_radps_rthz = config.profile.imu.gyro_noise_density_radps_rthz;
    noise.accel_noise_density_mps2_rthz = config.profile.imu.accel_noise_density_mps2_rthz;
  }
  return noise;
}

// MJCF geom group of the gripper's visual (drawn in the chase camera while it holds the payload).
constexpr int kGripperGeomGroup = 3;

// Seeds of the profile's own generators, apart from the sensor noise stream.
uint64_t DerivedSeed(uint64_t seed, uint64_t salt) { return seed * 0x9E3779B97F4A7C15ULL + salt; }

}  // namespace

World::World(const WorldConfig& config)
    : config_(config),
      world_params_(config.params),
      rng_(config.seed),
      imu_(ImuNoise(config), 1.0 / config.rates.imu.rate_hz, &rng_),
      vio_(config.noise, config.rates.vio.latency_s, &rng_),
      sensor_clock_(config.rates.physics_hz),
      vio_loop_(sensor_clock_.AddLoop("vio", config.rates.vio.rate_hz, TickRounding::kAtOrAfter)) {
  // the physics step is the MJCF's; the table must agree (checked below), and the IMU averages
  // a whole number of steps
  const double imu_steps = config.rates.physics_hz / config.rates.imu.rate_hz;
  if (!(imu_steps >= 1.0) || std::abs(imu_steps - std::round(imu_steps)) > 1e-9) {
    throw InputError("", "rates.imu", "the IMU rate must divide the physics rate");
  }
  imu_steps_ = static_cast<int>(std::lround(imu_steps));
  // the rate loop's own gyro (PX4 rate loop): the IMU's part at the loop's rate
  if (config.profile.rate_loop.px4) {
    const double steps = config.rates.physics_hz / config.profile.rate_loop.rate_hz;
    if (!(steps >= 1.0) || std::abs(steps - std::round(steps)) > 1e-9) {
      throw InputError("", "world.rate_loop.rate_hz", "the rate must divide the physics rate");
    }
    rate_gyro_steps_ = static_cast<int>(std::lround(steps));
    // discrete white noise of the same density at this rate: sigma = density / sqrt(period)
    rate_gyro_sigma_radps_ = ImuNoise(config).gyro_noise_density_radps_rthz /
                             std::sqrt(1.0 / config.profile.rate_loop.rate_hz);
  }
  InstallWarningHandler();
  const std::string& file = config_.scene_path;

  // load the MJCF; any load error or warning is bad input naming the file
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
      std::abs(config.rates.physics_hz * kPhysicsDt_s - 1.0) > 1e-12) {
    mj_deleteModel(model_);
    throw InputError(file, "option.timestep", "must be 0.001 s (World::kPhysicsDt_s)");
  }

  // named elements the world drives
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

  // the world's own parameters: flight params, the profile's mismatch draw, then the scenario's
  // explicit overrides (which win over the draw)
  DrawMismatch();
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

World::~World() {
  renderer_.reset();
  if (subframe_data_ != nullptr) mj_deleteData(subframe_data_);
  if (data_ != nullptr) mj_deleteData(data_);
  if (model_ != nullptr) mj_deleteModel(model_);
}

void World::ApplyWorldParams() {
  const Params& p = world_params_;
  model_->opt.gravity[0] = 0;
  model_->opt.gravity[1] = 0;
  model_->opt.gravity[2] = -p.gravity_mps2;

  // quadrotor mass and inertia
  model_->body_mass[ids_.quad_body] = p.quad_mass_kg;
  for (int i = 0; i < 3; ++i) model_->body_inertia[3 * ids_.quad_body + i] = p.inertia_B_kgm2(i);

  // payload: a solid sphere of the params' mass and radius
  model_->body_mass[ids_.payload_body] = p.payload_mass_kg;
  for (int i = 0; i < 3; ++i) {
    model_->body_inertia[3 * ids_.payload_body + i] =
        0.4 * p.payload_mass_kg * p.payload_radius_m * p.payload_radius_m;
  }
  const int sphere = mj_name2id(model_, mjOBJ_GEOM, "payload_sphere");
  if (sphere >= 0) {
    model_->geom_size[3 * sphere] = p.payload_radius_m;
    model_->geom_rbound[sphere] = p.payload_radius_m;
  }
  const int box = mj_name2id(model_, mjOBJ_GEOM, "quadrotor_box");
  if (box >= 0) {
    for (int i = 0; i < 3; ++i) model_->geom_size[3 * box + i] = p.body_half_size_m(i);
    model_->geom_rbound[box] = p.body_half_size_m.norm();
  }

  // cable length = the tendon's upper limit
  model_->tendon_range[2 * ids_.cable_tendon + 0] = 0.0;
  model_->tendon_range[2 * ids_.cable_tendon + 1] = p.cable_length_m;

  // rotors: thrust range from the motor bounds, sites at the params' arm length, yaw reaction
  // torque k_m / k_f per newton (the scene file holds the defaults; a --params file may differ)
  for (int i = 0; i < 4; ++i) {
    const int a = ids_.rotor_actuator[i];
    const int site = model_->actuator_trnid[2 * a];
    const Eigen::Vector3d r_B = RotorPosition_B(p, i);
    for (int k = 0; k < 3; ++k) model_->site_pos[3 * site + k] = r_B(k);
    const double k_f = p.k_f_N_per_radps2 * rotor_kf_factor_(i);
    const double k_m = p.k_m_Nm_per_radps2 * rotor_km_factor_(i);
    model_->actuator_gear[6 * a + 5] = RotorSpin(i) * k_m / k_f;
    model_->actuator_ctrlrange[2 * a + 0] = k_f * p.motor_speed_min_radps * p.motor_speed_min_radps;
    model_->actuator_ctrlrange[2 * a + 1] = k_f * p.motor_speed_max_radps * p.motor_speed_max_radps;
  }

  // contact between payload and vehicle: the payload (contype 4) meets the body box and the rotor
  // disks when their conaffinity has bit 4; the disks never touch the ground (contype 0)
  // Solver settings for these contacts at the 1 ms step (checked by sim/tests/contact_test.cc):
  // the payload's contacts are as stiff as MuJoCo resolves at this step (time constant 2 steps,
  // critically damped: a hard ball against a carbon frame, no rebound of a soft contact), and the
  // vehicle's geoms start their contact kContactMargin_m before the surfaces meet, so a payload
  // arriving at up to kContactMargin_m per step is stopped before it overlaps the vehicle (the
  // body's contact with the ground, a crash, then also counts from kContactMargin_m).
  if (config_.profile.contact.enabled) {
    constexpr double kMargin_m = kContactMargin_m;
    model_->geom_conaffinity[ids_.quad_box_geom] |= 4;
    model_->geom_margin[ids_.quad_box_geom] = kMargin_m;
    for (int i = 0; i < 4; ++i) {
      model_->geom_contype[ids_.rotor_disc_geom[i]] = 0;
      model_->geom_conaffinity[ids_.rotor_disc_geom[i]] = 4;
      model_->geom_margin[ids_.rotor_disc_geom[i]] = kMargin_m;
    }
    model_->geom_solref[mjNREF * ids_.payload_geom + 0] = 2 * kPhysicsDt_s;
    model_->geom_solref[mjNREF * ids_.payload_geom + 1] = 1.0;
    // its solref wins in every pair it is in (MuJoCo mixes a pair's solref by solmix)
    model_->geom_solmix[ids_.payload_geom] = 1e3;
  }

  // payload camera: field of view, image size, and pose in the body. MuJoCo's camera axes are
  // (x right, y up, looking along -z): R_B,mjcam = R_BC * diag(1, -1, -1) with C OpenCV's.
  const int cam = ids_.payload_camera;
  model_->cam_fovy[cam] = p.camera_fovy_deg;
  for (int k = 0; k < 3; ++k) model_->cam_pos[3 * cam + k] = p.t_BC_B_m(k);
  const Eigen::Matrix3d R_B_mjcam = p.R_BC * Eigen::Vector3d(1, -1, -1).asDiagonal();
  const Eigen::Quaterniond q_B_mjcam(R_B_mjcam);
  model_->cam_quat[4 * cam + 0] = q_B_mjcam.w();
  model_->cam_quat[4 * cam + 1] = q_B_mjcam.x();
  model_->cam_quat[4 * cam + 2] = q_B_mjcam.y();
  model_->cam_quat[4 * cam + 3] = q_B_mjcam.z();
  model_->vis.global.offwidth = p.camera_width_px;
  model_->vis.global.offheight = p.camera_height_px;

  // derived constants (subtree masses, invweight0 used by the constraint softness)
  mj_setConst(model_, data_);
}

void World::DrawMismatch() {
  // a generator of its own, so the sensor noise stream is the same with and without mismatch
  std::mt19937_64 rng(DerivedSeed(config_.seed, 0x6D69736D61746368ULL));
  std::normal_distribution<double> normal(0.0, 1.0);
  const MismatchProfile& m = config_.profile.mismatch;
  if (m.enabled) {
    Params& p = world_params_;
    p.payload_mass_kg = std::max(1e-3, p.payload_mass_kg + m.payload_mass_sigma_kg * normal(rng));
    p.cable_length_m = std::max(0.05, p.cable_length_m + m.cable_length_sigma_m * normal(rng));
    p.quad_mass_kg = std::max(0.05, p.quad_mass_kg + m.quad_mass_sigma_kg * normal(rng));
    for (int i = 0; i < 3; ++i) {
      p.inertia_B_kgm2(i) *= std::max(0.2, 1.0 + m.inertia_sigma_fraction * normal(rng));
    }
    p.k_f_N_per_radps2 *= std::max(0.2, 1.0 + m.thrust_coefficient_sigma_fraction * normal(rng));
    for (int i = 0; i < 3; ++i) p.t_BC_B_m(i) += m.camera_position_sigma_m * normal(rng);
    Eigen::Vector3d dtheta_B;
    for (int i = 0; i < 3; ++i) dtheta_B(i) = m.camera_angle_sigma_rad * normal(rng);
    if (dtheta_B.norm() > 0.0) {
      p.R_BC =
          Eigen::AngleAxisd(dtheta_B.norm(), dtheta_B.normalized()).toRotationMatrix() * p.R_BC;
    }
  }
  const ActuationProfile& a = config_.profile.actuation;
  if (a.enabled) {
    for (int i = 0; i < 4; ++i) {
      rotor_kf_factor_(i) = std::max(0.2, 1.0 + a.thrust_coefficient_spread * normal(rng));
      rotor_km_factor_(i) = std::max(0.2, 1.0 + a.torque_coefficient_spread * normal(rng));
    }
  }
}

double World::BatterySpeedFactor() const {
  const ActuationProfile& a = config_.profile.actuation;
  if (!a.enabled) return 1.0;
  return std::max(0.0, 1.0 - a.battery_voltage_drop_per_s * step_ * kPhysicsDt_s);
}

double World::PayloadQuadDistance() const {
  const Eigen::Vector3d p_WL_W(data_->xpos + 3 * ids_.payload_body);
  const double radius_m = model_->geom_size[3 * ids_.payload_geom];
  // the payload centre in a geom's frame: R_WG^T (p_WL - p_WG)
  auto in_geom = [&](int g) {
    const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R_WG(data_->geom_xmat +
                                                                              9 * g);
    return Eigen::Vector3d(R_WG.transpose() * (p_WL_W - Eigen::Vector3d(data_->geom_xpos + 3 * g)));
  };
  const int box = ids_.quad_box_geom;
  double d = BoxSignedDistance(in_geom(box), Eigen::Vector3d(model_->geom_size + 3 * box));
  for (int i = 0; i < 4; ++i) {
    const int g = ids_.rotor_disc_geom[i];
    d = std::min(d, CylinderSignedDistance(in_geom(g), model_->geom_size[3 * g],
                                           model_->geom_size[3 * g + 1]));
  }
  return d - radius_m;
}

void World::UpdateGripperContact() {
  if (ids_.gripper_geom < 0 || !config_.profile.contact.enabled) return;
  // The rod stands for the hand: while it holds the payload the weld alone acts (no contact
  // fights it); when it lets go the hand opens and withdraws, so the rod turns solid only once
  // the payload is clear of it. From then on it stops the payload (contype 4) and the
  // quadrotor's body (contype 2), which is a crash.
  // A gripper no event has used in this run (grab or move) is not there at all (no hand).
  if (gripper_active() || !gripper_used_) {
    gripper_solid_ = false;
  } else if (!gripper_solid_) {
    gripper_solid_ = PayloadGripperDistance() > 0.0;
  }
  model_->geom_contype[ids_.gripper_geom] = 0;
  model_->geom_conaffinity[ids_.gripper_geom] = gripper_solid_ ? (2 | 4) : 0;
}

double World::PayloadGripperDistance() const {
  // payload sphere against the rod's capsule (axis along its frame's z, half-length size[1])
  const int g = ids_.gripper_geom;
  const Eigen::Map<const Eigen::Vector3d> c(data_->geom_xpos + 3 * g);
  const Eigen::Vector3d axis(data_->geom_xmat[9 * g + 2], data_->geom_xmat[9 * g + 5],
                             data_->geom_xmat[9 * g + 8]);
  const double half_length_m = model_->geom_size[3 * g + 1];
  const double radius_m = model_->geom_size[3 * g + 0];
  const Eigen::Map<const Eigen::Vector3d> p(data_->qpos + ids_.payload_jnt_qpos);
  const double s = std::clamp((p - c).dot(axis), -half_length_m, half_length_m);
  return (p - (c + s * axis)).norm() - radius_m - world_params_.payload_radius_m;
}

void World::UpdateContacts() {
  bool now[5] = {false, false, false, false, false};  // the ContactCounts fields, in order
  bool rotor_strike = false;
  for (int i = 0; i < data_->ncon; ++i) {
    const mjContact& c = data_->contact[i];
    for (const auto& [a, b] : {std::pair{c.geom1, c.geom2}, std::pair{c.geom2, c.geom1}}) {
      if (a == ids_.payload_geom) {
        if (b == ids_.quad_box_geom) now[0] = true;
        for (int r = 0; r < 4; ++r) rotor_strike |= b == ids_.rotor_disc_geom[r];
        if (b == ids_.ground_geom) now[2] = true;
        if (b == ids_.gripper_geom) now[4] = true;
      }
      if (a == ids_.ground_geom && model_->geom_bodyid[b] == ids_.quad_body) now[3] = true;
    }
  }
  now[1] = rotor_strike;
  int* counts[5] = {&contact_counts_.payload_body, &contact_counts_.payload_rotor,
                    &contact_counts_.payload_ground, &contact_counts_.quad_ground,
                    &contact_counts_.payload_gripper};
  for (int k = 0; k < 5; ++k) {
    if (now[k] && !touching_[k]) ++*counts[k];
    touching_[k] = now[k];
  }
  payload_quad_min_distance_m_ = std::min(payload_quad_min_distance_m_, PayloadQuadDistance());
  if (rotor_strike) LatchCrash("rotor_strike");
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
  vio_.SetDrift(config_.profile.vio, DerivedSeed(config_.seed, 0x76696F));
  imu_queue_.clear();
  wind_rng_.seed(DerivedSeed(config_.seed, 0x77696E64));
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
  rate_gyro_rng_.seed(DerivedSeed(config_.seed, 0x726174656779ULL));
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

void World::UpdateGripper() {
  if (!gripper_moving_) return;
  const int64_t span = std::max<int64_t>(1, gripper_end_step_ - gripper_start_step_);
  const double s = std::clamp(static_cast<double>(step_ - gripper_start_step_) / span, 0.0, 1.0);
  // minimum-jerk profile: zero velocity and acceleration at both ends
  const double blend = s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
  const Eigen::Vector3d p = gripper_from_W_m_ + blend * (gripper_to_W_m_ - gripper_from_W_m_);
  for (int i = 0; i < 3; ++i) data_->mocap_pos[3 * ids_.gripper_mocap + i] = p(i);
  if (s >= 1.0) gripper_moving_ = false;
}

Eigen::Vector3d World::Wind_W_mps() const {
  const WindProfile& w = config_.profile.wind;
  const Eigen::Vector3d event_W =
      step_ < event_wind_end_step_ ? event_wind_W_mps_ : Eigen::Vector3d::Zero();
  return Eigen::Vector3d(w.mean_x_mps, w.mean_y_mps, w.mean_z_mps) + gust_W_mps_ + event_W;
}

void World::SetWindVelocity(const Eigen::Vector3d& velocity_W_mps, double duration_s) {
  if (!velocity_W_mps.allFinite() || !std::isfinite(duration_s)) {
    throw std::invalid_argument("World::SetWindVelocity: non-finite velocity or duration");
  }
  event_wind_W_mps_ = velocity_W_mps;
  event_wind_end_step_ = step_ + std::max<int64_t>(0, std::llround(duration_s / kPhysicsDt_s));
}

void World::ApplyAerodynamics() {
  const WindProfile& wind = config_.profile.wind;
  if (!config_.profile.aero.enabled && wind.gust_sigma_mps <= 0.0) return;  // no air
  const Truth truth = GetTruth();
  const SystemState& s = truth.state;
  // gust: per axis first-order Gauss-Markov, exact for the step: x' = a x + sigma sqrt(1-a^2) n,
  // a = exp(-dt / tau), tau = L / airspeed (Dryden's low-altitude form at the vehicle's airspeed)
  if (wind.gust_sigma_mps > 0.0) {
    const Eigen::Vector3d mean(wind.mean_x_mps, wind.mean_y_mps, wind.mean_z_mps);
    const double airspeed_mps = std::max(wind.gust_min_speed_mps, (s.v_WQ_W - mean).norm());
    std::normal_distribution<double> unit(0.0, 1.0);
    for (int i = 0; i < 3; ++i) {
      const bool vertical = i == 2;
      const double sigma = wind.gust_sigma_mps * (vertical ? wind.gust_vertical_sigma_ratio : 1.0);
      const double length_m = vertical ? wind.gust_vertical_length_m : wind.gust_length_m;
      const double a = std::exp(-kPhysicsDt_s * airspeed_mps / length_m);
      gust_W_mps_(i) = a * gust_W_mps_(i) + sigma * std::sqrt(1.0 - a * a) * unit(wind_rng_);
    }
  }
  const AeroProfile& aero = config_.profile.aero;
  if (!aero.enabled) return;
  const Eigen::Vector3d wind_W = Wind_W_mps();
  const Eigen::Matrix3d R_WB = s.q_WB.normalized().toRotationMatrix();
  const Eigen::Vector3d air_B = R_WB.transpose() * (s.v_WQ_W - wind_W);  // airspeed, body  (3)

  // rotor drag: linear in the airspeed in the rotor plane (Faessler et al., RA-L 2018)
  Eigen::Vector3d f_B(-aero.rotor_drag_x_Nspm * air_B.x(), -aero.rotor_drag_y_Nspm * air_B.y(), 0);
  // body drag: quadratic, -0.5 rho |v| diag(Cd_i A_i) v over the box's faces
  const Eigen::Vector3d& h = world_params_.body_half_size_m;
  const Eigen::Vector3d cd_area_B_m2(aero.body_drag_coefficient_xy * 4 * h.y() * h.z(),
                                     aero.body_drag_coefficient_xy * 4 * h.x() * h.z(),
                                     aero.body_drag_coefficient_z * 4 * h.x() * h.y());
  f_B -= 0.5 * aero.air_density_kgpm3 * air_B.norm() * cd_area_B_m2.cwiseProduct(air_B);
  aero_quad_W_N_ = R_WB * f_B;
  // payload drag: a sphere
  const Eigen::Vector3d air_L_W = s.v_WL_W - wind_W;
  const double r = world_params_.payload_radius_m;
  aero_payload_W_N_ = -0.5 * aero.air_density_kgpm3 * aero.payload_drag_coefficient * M_PI * r * r *
                      air_L_W.norm() * air_L_W;
  for (int i = 0; i < 3; ++i) {
    data_->xfrc_applied[6 * ids_.quad_body + i] += aero_quad_W_N_(i);
    data_->xfrc_applied[6 * ids_.payload_body + i] += aero_payload_W_N_(i);
  }
}

void World::ApplyDisturbances() {
  mju_zero(data_->xfrc_applied, 6 * model_->nbody);
  ApplyAerodynamics();
  for (const TimedForce& f : forces_) {
    if (step_ >= f.end_step) continue;
    const int body = f.body == Body::kQuadrotor ? ids_.quad_body : ids_.payload_body;
    for (int i = 0; i < 3; ++i) data_->xfrc_applied[6 * body + i] += f.force_W_N(i);
  }
  forces_.erase(std::remove_if(forces_.begin(), forces_.end(),
                               [this](const TimedForce& f) { return step_ + 1 >= f.end_step; }),
                forces_.end());
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

void World::ApplyImpulse(Body body, const Eigen::Vector3d& impulse_W_Ns, double duration_s) {
  if (!impulse_W_Ns.allFinite() || !std::isfinite(duration_s)) {
    throw std::invalid_argument("World::ApplyImpulse: non-finite impulse or duration");
  }
  const int64_t steps = std::max<int64_t>(1, std::llround(duration_s / kPhysicsDt_s));
  forces_.push_back({body, impulse_W_Ns / (steps * kPhysicsDt_s), step_ + steps});
}

void World::SetWind(const Eigen::Vector3d& force_W_N, double duration_s) {
  if (!force_W_N.allFinite() || !std::isfinite(duration_s)) {
    throw std::invalid_argument("World::SetWind: non-finite force or duration");
  }
  const int64_t steps = std::max<int64_t>(0, std::llround(duration_s / kPhysicsDt_s));
  forces_.push_back({Body::kQuadrotor, force_W_N, step_ + steps});
}

void World::GripperGrab() {
  // put the mocap body on the payload's current pose, then switch the weld on
  const mjtNum* qpos = data_->qpos + ids_.payload_jnt_qpos;
  for (int i = 0; i < 3; ++i) data_->mocap_pos[3 * ids_.gripper_mocap + i] = qpos[i];
  for (int i = 0; i < 4; ++i) data_->mocap_quat[4 * ids_.gripper_mocap + i] = qpos[3 + i];
  gripper_moving_ = false;
  model_->eq_active[ids_.gripper_weld] = 1;
  gripper_used_ = true;
  UpdateGripperContact();
}

void World::GripperMove(const Eigen::Vector3d& to_W_m, double duration_s) {
  if (!to_W_m.allFinite() || !std::isfinite(duration_s)) {
    throw std::invalid_argument("World::GripperMove: non-finite target or duration");
  }
  gripper_from_W_m_ = Eigen::Map<const Eigen::Vector3d>(data_->mocap_pos + 3 * ids_.gripper_mocap);
  gripper_to_W_m_ = to_W_m;
  gripper_start_step_ = step_;
  gripper_end_step_ = step_ + std::max<int64_t>(1, std::llround(duration_s / kPhysicsDt_s));
  gripper_moving_ = true;
  gripper_used_ = true;
  UpdateGripperContact();
}

void World::GripperRelease() {
  model_->eq_active[ids_.gripper_weld] = 0;
  gripper_moving_ = false;
}

bool World::gripper_active() const { return model_->eq_active[ids_.gripper_weld] != 0; }

CrashStatus World::Crash() const { return crash_; }

void World::LatchCrash(const std::string& reason) {
  if (crash_.crashed) return;
  crash_.crashed = true;
  crash_.time_s = time_s();
  crash_.reason = reason;
}

void World::CheckWarnings() {
  for (int i = 0; i < mjNWARNING; ++i) {
    const int n = data_->warning[i].number;
    if (n == warning_count_[i]) continue;
    warning_count_[i] = n;
    const std::string text = TakeWarnings();
    if (i == mjWARN_BADQPOS || i == mjWARN_BADQVEL || i == mjWARN_BADQACC) {
      // MuJoCo has reset mjData: the state went non-finite (DESIGN.md section 6: a crash)
      LatchCrash("non-finite state (MuJoCo: " + text + ")");
      continue;
    }
    throw std::runtime_error("MuJoCo warning at t = " + std::to_string(time_s()) + " s: " + text);
  }
}

void World::CheckCrash() {
  if (crash_.crashed) return;
  const Truth t = GetTruth();
  const SystemState& s = t.state;
  if (!s.AllFinite()) return LatchCrash("non-finite state");

  // any contact of the quadrotor body (ground or an obstacle); the payload against the body is
  // contact, not a crash (against a rotor: UpdateContacts), unless the payload lies on the
  // ground: then the body has struck the ground through it
  bool payload_on_ground = false, body_on_payload = false;
  for (int i = 0; i < data_->ncon; ++i) {
    const mjContact& c = data_->contact[i];
    const int b1 = model_->geom_bodyid[c.geom1], b2 = model_->geom_bodyid[c.geom2];
    const bool has_payload = c.geom1 == ids_.payload_geom || c.geom2 == ids_.payload_geom;
    payload_on_ground |=
        has_payload && (c.geom1 == ids_.ground_geom || c.geom2 == ids_.ground_geom);
    if (b1 != ids_.quad_body && b2 != ids_.quad_body) continue;
    const int other = b1 == ids_.quad_body ? c.geom2 : c.geom1;
    if (other == ids_.payload_geom) {
      body_on_payload = true;
      continue;
    }
    const char* name = mj_id2name(model_, mjOBJ_GEOM, other);
    return LatchCrash(std::string("quadrotor contact with ") + (name ? name : "a geom"));
  }
  if (payload_on_ground && body_on_payload) {
    return LatchCrash("quadrotor contact with the payload lying on the ground");
  }

  // tilt past 90 deg: body z points below the horizon
  if (s.q_WB.normalized().toRotationMatrix()(2, 2) < 0.0) return LatchCrash("tilt > 90 deg");

  // arena 20 x 20 x 10 m
  constexpr double kArenaHalfWidth_m = 10.0, kArenaHeight_m = 10.0;
  const Eigen::Vector3d& p = s.p_WQ_W;
  if (std::abs(p.x()) > kArenaHalfWidth_m || std::abs(p.y()) > kArenaHalfWidth_m || p.z() < 0.0 ||
      p.z() > kArenaHeight_m) {
    return LatchCrash("left the 20x20x10 m arena");
  }
}

void World::RandomizeAppearance() {
  // what the camera sees varies, the physics does not: floor shade and checker scale, and the
  // lights' strength and direction (no saturated colour: the detector looks for red)
  std::mt19937_64 rng(DerivedSeed(config_.seed, 0x6C69676874ULL));
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int floor_mat = model_->geom_matid[ids_.ground_geom];
  if (floor_mat >= 0) {
    const double shade = 0.6 + 0.8 * u(rng);  // darker to brighter grey, a slight warm/cool cast
    const double cast = 0.08 * (u(rng) - 0.5);
    model_->mat_rgba[4 * floor_mat + 0] = static_cast<float>(std::min(1.0, shade * (1 + cast)));
    model_->mat_rgba[4 * floor_mat + 1] = static_cast<float>(std::min(1.0, shade));
    model_->mat_rgba[4 * floor_mat + 2] = static_cast<float>(std::min(1.0, shade * (1 - cast)));
    const double repeat = 10.0 + 30.0 * u(rng);  // checker squares 0.25-1 m
    model_->mat_texrepeat[2 * floor_mat + 0] = static_cast<float>(repeat);
    model_->mat_texrepeat[2 * floor_mat + 1] = static_cast<float>(repeat);
  }
  const double head_diffuse = 0.35 + 0.5 * u(rng), head_ambient = 0.2 + 0.3 * u(rng);
  for (int k = 0; k < 3; ++k) {
    model_->vis.headlight.diffuse[k] = static_cast<float>(head_diffuse);
    model_->vis.headlight.ambient[k] = static_cast<float>(head_ambient);
  }
  for (int l = 0; l < model_->nlight; ++l) {
    const double strength = 0.2 + 0.6 * u(rng);
    for (int k = 0; k < 3; ++k) model_->light_diffuse[3 * l + k] = static_cast<float>(strength);
    const double azimuth = 2.0 * M_PI * u(rng), elevation = 0.6 + 0.9 * u(rng);  // rad
    model_->light_dir[3 * l + 0] = std::cos(azimuth) * std::cos(elevation);
    model_->light_dir[3 * l + 1] = std::sin(azimuth) * std::cos(elevation);
    model_->light_dir[3 * l + 2] = -std::sin(elevation);
  }
}

cv::Mat World::RenderPayloadCamera() {
  cv::Mat bgr;
  RenderPayloadCamera(&bgr, cv::Rect());
  return bgr;
}

Eigen::Vector2d World::PayloadImageMotionPx(cv::Rect* region) const {
  const Params& p = world_params_;
  const double f_px =
      camera_image_ != nullptr ? camera_image_->render_focal_px() : p.CameraFocalPx();
  const double exposure_s = config_.profile.camera.exposure_s;
  // camera pose and velocity from the quadrotor's
  const double* q = data_->xquat + 4 * ids_.quad_body;
  const Eigen::Matrix3d R_WB =
      Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
  const Eigen::Map<const Eigen::Vector3d> p_WQ_W(data_->xpos + 3 * ids_.quad_body);
  const Eigen::Map<const Eigen::Vector3d> p_WL_W(data_->xpos + 3 * ids_.payload_body);
  const double* vq = data_->qvel + ids_.quad_jnt_dof;  // linear (world), angular (body)
  const double* vl = data_->qvel + ids_.payload_jnt_dof;
  const Eigen::Vector3d v_WQ_W(vq[0], vq[1], vq[2]), w_B(vq[3], vq[4], vq[5]);
  const Eigen::Vector3d v_WL_W(vl[0], vl[1], vl[2]);
  const Eigen::Matrix3d R_WC = R_WB * p.R_BC;
  const Eigen::Vector3d p_WC_W = p_WQ_W + R_WB * p.t_BC_B_m;
  const Eigen::Vector3d v_WC_W = v_WQ_W + R_WB * w_B.cross(p.t_BC_B_m);
  const Eigen::Vector3d w_C = p.R_BC.transpose() * w_B;
  const Eigen::Vector3d p_CL_C = R_WC.transpose() * (p_WL_W - p_WC_W);
  // d/dt of p_CL_C: relative velocity seen from the rotating camera
  const Eigen::Vector3d v_CL_C = R_WC.transpose() * (v_WL_W - v_WC_W) - w_C.cross(p_CL_C);
  const double z = p_CL_C.z();
  const double cx = 0.5 * p.camera_width_px, cy = 0.5 * p.camera_height_px;
  if (region != nullptr) *region = cv::Rect();
  if (!(z > p.payload_radius_m)) return Eigen::Vector2d::Zero();
  const Eigen::Vector2d rate_px(f_px * (v_CL_C.x() * z - p_CL_C.x() * v_CL_C.z()) / (z * z),
                                f_px * (v_CL_C.y() * z - p_CL_C.y() * v_CL_C.z()) / (z * z));
  if (region != nullptr) {
    const double r_px =
        f_px * p.payload_radius_m / std::sqrt(z * z - std::pow(p.payload_radius_m, 2));
    const double u = cx + f_px * p_CL_C.x() / z, v = cy + f_px * p_CL_C.y() / z;
    // a sphere off-axis images as an ellipse up to 1 / cos^2 of the ray angle wider: 2 r covers
    const int half = static_cast<int>(std::ceil(2.0 * r_px)) + 2;
    *region = cv::Rect(static_cast<int>(u) - half, static_cast<int>(v) - half, 2 * half, 2 * half) &
              cv::Rect(0, 0, p.camera_width_px, p.camera_height_px);
  }
  return rate_px * exposure_s;
}

void World::RenderPayloadCamera(cv::Mat* bgr, const cv::Rect& region) {
  using Clock = std::chrono::steady_clock;
  const auto ms = [](Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
  };
  const CameraImageProfile& profile = config_.profile.camera;
  if (camera_image_ == nullptr) {
    camera_image_ = std::make_unique<CameraImageModel>(
        world_params_, profile, DerivedSeed(config_.seed, 0x63616D657261ULL));
    // the render is a pinhole image wide enough to cover the distorted sensor
    model_->cam_fovy[ids_.payload_camera] = camera_image_->render_fovy_deg();
  }
  const int w = model_->vis.global.offwidth, h = model_->vis.global.offheight;
  // noise keyed by the physics step: a region and the whole frame of one instant agree
  const uint64_t frame = static_cast<uint64_t>(step_);
  const auto t0 = Clock::now();
  double render_ms = 0.0;
  if (profile.exposure_s > 0.0 && profile.motion_blur_subframes >= 2) {
    // reference motion blur: the average of renders at sub-frame times across the exposure,
    // every body moved with its current velocity (the exposure is centred on now); always the
    // whole frame, which a region request reads its part of
    if (subframe_data_ == nullptr) subframe_data_ = mj_makeData(model_);
    const int n = profile.motion_blur_subframes;
    subframe_sum_.create(h, w, CV_32FC3);
    subframe_sum_.setTo(cv::Scalar::all(0.0));
    for (int i = 0; i < n; ++i) {
      const double dt_s = ((i + 0.5) / n - 0.5) * profile.exposure_s;
      mj_copyData(subframe_data_, model_, data_);
      mj_integratePos(model_, subframe_data_->qpos, subframe_data_->qvel, dt_s);
      mj_kinematics(model_, subframe_data_);
      mj_comPos(model_, subframe_data_);
      mj_camlight(model_, subframe_data_);
      mj_tendon(model_, subframe_data_);
      renderer_->Render(subframe_data_, ids_.payload_camera, w, h, profile.draw_cable, &subframe_);
      cv::accumulate(subframe_, subframe_sum_);
    }
    subframe_sum_.convertTo(pinhole_, CV_8UC3, 1.0 / n);
    const auto t1 = Clock::now();
    render_ms = ms(t0, t1);
    camera_image_->ApplyOptics(pinhole_, frame, bgr);
  } else {
    cv::Rect blur_region;
    const Eigen::Vector2d blur_px =
        profile.exposure_s > 0.0 ? PayloadImageMotionPx(&blur_region) : Eigen::Vector2d::Zero();
    const cv::Rect render_region =
        region.area() > 0 ? camera_image_->RenderRegion(region, blur_px) : cv::Rect();
    renderer_->Render(data_, ids_.payload_camera, w, h, profile.draw_cable, &pinhole_,
                      render_region);
    const auto t1 = Clock::now();
    render_ms = ms(t0, t1);
    camera_image_->Apply(pinhole_, blur_px, blur_region, frame, bgr, region);
  }
  camera_timing_.render_ms = render_ms;
  camera_timing_.image_model_ms = ms(t0, Clock::now()) - render_ms;
}

cv::Mat World::RenderChaseCamera(int width_px, int height_px) {
  // the gripper (group 3) while it holds the payload
  renderer_->SetGeomGroupVisible(kGripperGeomGroup, model_->eq_active[ids_.gripper_weld] != 0);
  const cv::Mat frame = renderer_->Render(data_, ids_.chase_camera, width_px, height_px);
  renderer_->SetGeomGroupVisible(kGripperGeomGroup, false);
  return frame;
}

}  // namespace hpa::sim
