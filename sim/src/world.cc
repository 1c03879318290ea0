// World: the MuJoCo model and data, the lockstep physics step and its order over the components,
// state and the sensors' delivery.

#include "hpa/sim/world.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <string>

#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/models/rotor_model.h"
#include "hpa/models/seed_streams.h"
#include "specific_force.h"
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
    : config_(config), world_params_(config.params), sensors_(config), faults_(config.seed) {
  // read at the start of a tick, delivered after the sensors' lines
  gripper_sensor_ = std::make_unique<GripperSensor>(config);
  gripper_line_ = sensors_.AddLine(gripper_sensor_->declaration().latency_s);
  camera_ = std::make_unique<PayloadCameraSensor>(config);
  camera_line_ = sensors_.AddLine(camera_->declaration().latency_s);
  InstallWarningHandler();
  LoadScene();
  ResolveIds();
  // the world's own parameters: flight params, the profile's mismatch draw, then the scenario's
  // explicit overrides (which win over the draw)
  DrawMismatch();
  ApplyOverrides();
  data_ = mj_makeData(model_);
  // the vehicle's motors and rotors, bound to this world's rotors and clock
  VehicleBinding binding;
  binding.model = model_;
  binding.data = data_;
  for (int i = 0; i < 4; ++i)
    binding.rotor_actuator[static_cast<size_t>(i)] = ids_.rotor_actuator[i];
  binding.params = &world_params_;
  binding.actuation = &config_.profile.actuation;
  binding.faults = &faults_;
  binding.step = &step_;
  binding.t0_s = &t0_s_;
  vehicle_.emplace(binding);
  vehicle_->SetRotorFactors(rotor_kf_draw_, rotor_km_draw_);
  // the payload's contacts with this vehicle, the ground and the gripper
  ContactsBinding contacts;
  contacts.model = model_;
  contacts.data = data_;
  contacts.payload_body = ids_.payload_body;
  contacts.payload_geom = ids_.payload_geom;
  contacts.quad_body = ids_.quad_body;
  contacts.quad_box_geom = ids_.quad_box_geom;
  for (int i = 0; i < 4; ++i) {
    contacts.rotor_disc_geom[static_cast<size_t>(i)] = ids_.rotor_disc_geom[i];
  }
  contacts.ground_geom = ids_.ground_geom;
  contacts.gripper_geom = ids_.gripper_geom;
  contacts_.emplace(contacts);
  // the hand that grabs, carries and releases the payload
  GripperBinding hand;
  hand.model = model_;
  hand.data = data_;
  hand.mocap = ids_.gripper_mocap;
  hand.weld = ids_.gripper_weld;
  hand.rod_geom = ids_.gripper_geom;
  hand.payload_qpos = ids_.payload_jnt_qpos;
  hand.payload_radius_m = &world_params_.payload_radius_m;
  hand.contact = config_.profile.contact.enabled;
  hand.faults = &faults_;
  hand.step = &step_;
  hand.t0_s = &t0_s_;
  gripper_.emplace(hand);
  BindDisturbances();
  ApplyWorldParams();
  renderer_ = std::unique_ptr<Renderer>(new Renderer(*this));

  // start hovering 1 m up, payload hanging
  SystemState initial;
  initial.p_WQ_W = Eigen::Vector3d(0, 0, 1.0);
  initial.p_WL_W = initial.p_WQ_W - Eigen::Vector3d(0, 0, world_params_.cable_length_m);
  Reset(initial);
}

// Forces, impulses, velocity changes and the air on this world's quadrotor and payload.
void World::BindDisturbances() {
  DisturbancesBinding air;
  air.model = model_;
  air.data = data_;
  air.vehicles.push_back({ids_.quad_body, ids_.quad_jnt_qpos, ids_.quad_jnt_dof, &world_params_});
  air.payload_body = ids_.payload_body;
  air.payload_dof = ids_.payload_jnt_dof;
  air.payload_radius_m = &world_params_.payload_radius_m;
  air.aero = &config_.profile.aero;
  air.step = &step_;
  disturbances_.emplace(air, config_.profile.wind, config_.rates.physics_hz,
                        DeriveSeed(config_.seed, SeedStream::kWind));
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
  // each override within the range params.yaml declares for the field it replaces
  const auto apply = [&](const std::optional<double>& value, double Params::*member,
                         const char* key) {
    if (!value) return;
    const ParamDecl<Params>& d = FindParamDecl(ParamsTables(), member);
    if (!InDeclRange(d, *value)) {
      mj_deleteModel(model_);
      throw InputError("", key,
                       "expected " + ParamValueText(d.min) + " to " + ParamValueText(d.max) + " " +
                           d.unit + ", got " + ParamValueText(*value));
    }
    world_params_.*member = *value;
  };
  apply(config_.overrides.payload_mass_kg, &Params::payload_mass_kg, "world.payload_mass");
  apply(config_.overrides.cable_length_m, &Params::cable_length_m, "world.cable_length");
}

World::~World() {
  renderer_.reset();
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
  disturbances_->ClearForces();
  gripper_->Reset();
  sensors_.Reset();
  camera_->Reset();
  disturbances_->ResetWind();
  crash_ = CrashStatus{};
  faults_.Clear();

  // motors at hover speed of the simulated system
  const double w_hover = world_params_.HoverMotorSpeedRadps();
  SetState(initial.ToVector(), InputVector::Constant(w_hover));
  contacts_->Reset();
  gripper_->UpdateContact();
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
  vehicle_->SetSpeed(motor_speed_radps);
  vehicle_->WriteMotorControls();
  gripper_->Update();
  mj_forward(model_, data_);
  CheckWarnings();
}

void World::SetMotorSpeedCommand(const InputVector& w_cmd_radps) {
  vehicle_->SetCommand(w_cmd_radps);
}

void World::Step() {
  // state at t_k is current (mj_forward / mj_step1 ran): sample what the sensors need from it
  const SystemState before = GetTruth().state;

  // first-order motor lag; thrust to the actuators
  vehicle_->StepMotors();
  if (!faults_.empty() && faults_.TakeGripperRelease(time_s())) {
    gripper_->Open();  // a gripper fault lets go
  }
  vehicle_->WriteMotorControls();
  disturbances_->Apply();

  // dynamics at t_k and integration to t_{k+1}, then kinematics at t_{k+1}
  mj_step2(model_, data_);
  ++step_;
  gripper_->Update();
  mj_step1(model_, data_);
  CheckWarnings();

  // sensors, stamped with t_k (qacc from mj_step2 is the acceleration at t_k), each through
  // the delay line of its declared latency
  SensorInput in;
  in.t_k_s = t0_s_ + (step_ - 1) * kPhysicsDt_s;
  in.state = &before;
  in.specific_force_B_mps2 = SpecificForce_B(data_, ids_.quad_jnt_dof, before.q_WB,
                                             Eigen::Vector3d(0, 0, -world_params_.gravity_mps2));
  sensors_.Sample(in);
  if (contacts_->Update()) LatchCrash("rotor_strike");
  gripper_->UpdateContact();
  CheckCrash();
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
  s.payload_supported = gripper_->active();
  t.motor_speed_radps = vehicle_->motor_speed_radps();
  return t;
}

std::vector<SensorMessage> World::TakeDelivered() {
  std::vector<SensorMessage> out;
  TakeDelivered(&out);
  return out;
}

void World::TakeDelivered(std::vector<SensorMessage>* out) {
  sensors_.TakeDelivered(time_s(), &faults_, out);
}

void World::AddSensor(std::unique_ptr<Sensor> sensor) { sensors_.AddSensor(std::move(sensor)); }

std::vector<SensorMessage> World::TakeInFlight() {
  return sensors_.TakeInFlight(time_s(), &faults_);
}

std::optional<CameraCapture> World::CaptureTickStart(const cv::Rect& region) {
  sensors_.Push(gripper_line_, time_s(), gripper_sensor_->Sample(time_s(), gripper_->active()));
  std::optional<PayloadDetection> detection;
  std::optional<CameraCapture> capture = camera_->Capture(
      *this, step_, time_s(), region, faults_.empty() ? nullptr : &faults_, &detection);
  // the analytic camera's detection (or no camera's none) is read here; a rendered exposure's
  // reading comes back through QueueCameraMessage
  if (capture && !capture->exposure && !faults_.empty()) {
    faults_.OnCameraReading(time_s(), GetTruth().state, world_params_, false, &detection);
    if (detection) capture->detected = detection->found;
  }
  if (detection) {
    const double capture_time_s = detection->time_s;
    sensors_.Push(camera_line_, capture_time_s, std::move(*detection));
  }
  return capture;
}

void World::QueueCameraMessage(SensorMessage message) {
  double capture_time_s = 0.0;
  if (const auto* d = std::get_if<PayloadDetection>(&message)) {
    capture_time_s = d->time_s;
  } else if (const auto* f = std::get_if<CameraFrame>(&message)) {
    capture_time_s = f->capture_time_s;
  } else {
    throw std::invalid_argument("World::QueueCameraMessage: not a camera message");
  }
  if (!faults_.empty()) {
    std::optional<PayloadDetection> detection;
    if (const auto* d = std::get_if<PayloadDetection>(&message)) detection = *d;
    faults_.OnCameraReading(capture_time_s, GetTruth().state, world_params_, true, &detection);
  }
  sensors_.Push(camera_line_, capture_time_s, std::move(message));
}

}  // namespace hpa::sim
