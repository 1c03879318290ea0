// TeamWorld: the MuJoCo world of a team of quadrotors on their own cables carrying one payload
// (docs/cooperative.md), stepped like the single-vehicle World: 1 kHz, first-order motors, the
// same disturbances, onboard sensors, crash conditions and MuJoCo warning handling. Its scene,
// sensors and crash checks are in team_world_scene.cc, team_world_sensors.cc and
// team_world_crash.cc.

#include "hpa/sim/team_world.h"

#include <mujoco/mujoco.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "hpa/models/rotor_model.h"
#include "hpa/models/seed_streams.h"
#include "mismatch_draw.h"
#include "team_world_impl.h"

namespace hpa::sim {

namespace {

using I = CooperativeStateIndex;

}  // namespace

void TeamWorld::Impl::RequireVehicle(int vehicle, const char* caller) const {
  if (vehicle < 0 || vehicle >= n) {
    throw std::out_of_range(std::string(caller) + ": no vehicle " + std::to_string(vehicle));
  }
}

// Each vehicle's rotor speeds holding its weight and its taut cable's static share of the
// payload's: the cable tensions T that balance the payload's weight, force and moment about
// its centre, along the cables as they lie (minimum-norm least squares, negative shares
// clipped to zero); each vehicle then supplies |m_i g e3 + T_i u_i| (u_i: unit vector from
// its attachment point to it), shared equally by its four rotors.
std::vector<InputVector> TeamWorld::Impl::HoldingSpeeds_radps() const {
  const CooperativeTeam& team = config.team;
  std::vector<int> taut;
  std::vector<Eigen::Vector3d> u_W(n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d r = Block(vehicles[i]).head<3>() - AttachPoint_W(i);
    u_W[i] = r.norm() > 0 ? Eigen::Vector3d(r.normalized()) : Eigen::Vector3d::UnitZ();
    if (Taut(i)) taut.push_back(i);
  }
  Eigen::VectorXd tension_N = Eigen::VectorXd::Zero(n);
  if (!taut.empty()) {
    const Eigen::Vector3d p_L = Block(payload).head<3>();
    Eigen::MatrixXd A(6, static_cast<int>(taut.size()));
    for (size_t c = 0; c < taut.size(); ++c) {
      const int i = taut[c];
      A.col(static_cast<int>(c)) << u_W[i], (AttachPoint_W(i) - p_L).cross(u_W[i]);
    }
    Eigen::VectorXd b = Eigen::VectorXd::Zero(6);
    b(2) = team.payload_mass_kg * team.gravity_mps2;
    const Eigen::VectorXd t = A.completeOrthogonalDecomposition().solve(b);
    for (size_t c = 0; c < taut.size(); ++c) {
      tension_N(taut[c]) = std::max(0.0, t(static_cast<int>(c)));
    }
  }
  std::vector<InputVector> w(n);
  for (int i = 0; i < n; ++i) {
    const Params& p = params(i);
    const Eigen::Vector3d f_W =
        p.quad_mass_kg * p.gravity_mps2 * Eigen::Vector3d::UnitZ() + tension_N(i) * u_W[i];
    w[i] = RotorSpeedsFromWrench(p, Eigen::Vector4d(f_W.norm(), 0, 0, 0));
  }
  return w;
}

void TeamWorld::Impl::BindComponents() {
  // each vehicle's motors and rotors, reading its own faults
  for (int i = 0; i < n; ++i) {
    faults.push_back(std::make_unique<Faults>(config.seed));
    VehicleBinding binding;
    binding.model = m;
    binding.data = d;
    binding.rotor_actuator = rotor_actuator[static_cast<size_t>(i)];
    binding.params = &params(i);
    binding.actuation = &config.profile.actuation;
    binding.faults = faults.back().get();
    binding.step = &step;
    binding.t0_s = &t0_s;
    actuation.emplace_back(binding);
    actuation.back().SetRotorFactors(rotor_kf_draw[static_cast<size_t>(i)],
                                     rotor_km_draw[static_cast<size_t>(i)]);
  }
  // pushes, wind and drag on every vehicle and the payload
  DisturbancesBinding air;
  air.model = m;
  air.data = d;
  for (int i = 0; i < n; ++i) {
    const FreeBody& v = vehicles[static_cast<size_t>(i)];
    air.vehicles.push_back({v.body, v.qpos, v.dof, &params(i)});
  }
  air.payload_body = payload.body;
  air.payload_dof = payload.dof;
  air.payload_radius_m = &payload_radius_m;
  air.aero = &config.profile.aero;
  air.step = &step;
  disturbances.emplace(air, config.profile.wind, config.rates.physics_hz,
                       DeriveSeed(config.seed, SeedStream::kWind));
}

TeamWorld::TeamWorld(const TeamWorldConfig& config) : impl_(std::make_unique<Impl>()) {
  Impl& w = *impl_;
  ValidateTeamConfig(config);
  w.config = config;
  // the world's own numbers: the profile's mismatch draw per vehicle (the flight code keeps the
  // team as configured), and each vehicle's rotor spread
  w.config.team = DrawTeamMismatch(config.team, config.profile, config.seed, &w.rotor_kf_draw,
                                   &w.rotor_km_draw);
  w.n = static_cast<int>(config.team.vehicles.size());
  w.mocap_period_steps =
      static_cast<int>(std::lround(1.0 / (config.mocap.rate_hz * World::kPhysicsDt_s)));
  w.mocap_line = DelayLine<BodyReading>(config.mocap.latency_s);
  // the onboard sensors first: a bad rate is refused before MuJoCo holds anything
  w.MakeOnboardSensors();
  w.LoadScene();
  w.ResolveIds();
  // each vehicle's inertia as drawn (LoadScene compiled a balanced one)
  for (int i = 0; i < w.n; ++i) {
    for (int k = 0; k < 3; ++k) {
      w.m->body_inertia[3 * w.vehicles[static_cast<size_t>(i)].body + k] =
          w.params(i).inertia_B_kgm2(k);
    }
  }
  w.BindComponents();
  w.gyro_B_radps.assign(w.n, Eigen::Vector3d::Zero());

  // start hanging at rest, the payload 1 m up
  Reset(CooperativeModel(config.team).HangingState(Eigen::Vector3d(0, 0, 1.0)));
}

TeamWorld::~TeamWorld() {
  impl_->renderer.reset();  // it reads the model and data below
  if (impl_->d != nullptr) mj_deleteData(impl_->d);
  if (impl_->m != nullptr) mj_deleteModel(impl_->m);
}

int TeamWorld::VehicleCount() const { return impl_->n; }

void TeamWorld::Reset(const Eigen::VectorXd& x0) {
  Impl& w = *impl_;
  if (x0.size() != I::Size(w.n) || !x0.allFinite()) {
    throw std::invalid_argument("TeamWorld::Reset: the state must be " +
                                std::to_string(I::Size(w.n)) + " finite numbers, got " +
                                std::to_string(x0.size()));
  }
  mj_resetData(w.m, w.d);
  w.step = 0;
  w.d->time = 0.0;
  w.warning_count.assign(mjNWARNING, 0);
  w.crash = CrashStatus{};
  w.disturbances->ClearForces();
  w.disturbances->ResetWind();
  for (const std::unique_ptr<Faults>& f : w.faults) f->Clear();
  for (const std::unique_ptr<SensorSuite>& suite : w.onboard) suite->Reset();
  w.mocap_line.Clear();
  w.rng.seed(w.config.seed);
  w.normal.reset();

  // the bodies, then each vehicle's motors at the speed that holds it and its share
  w.SetBlock(w.payload, x0, 0);
  for (int i = 0; i < w.n; ++i) w.SetBlock(w.vehicles[i], x0, I::Vehicle(i));
  const std::vector<InputVector> holding_radps = w.HoldingSpeeds_radps();
  for (int i = 0; i < w.n; ++i) {
    w.actuation[static_cast<size_t>(i)].SetSpeed(holding_radps[static_cast<size_t>(i)]);
    w.actuation[static_cast<size_t>(i)].WriteMotorControls();
  }
  mj_forward(w.m, w.d);
  w.CheckWarnings();

  // this instant's sensor samples (the first motion-capture capture is at t = 0)
  w.SampleGyros();
  w.SampleMocap();
}

void TeamWorld::SetMotorSpeedCommand(int vehicle, const InputVector& w_cmd_radps) {
  Impl& w = *impl_;
  w.RequireVehicle(vehicle, "TeamWorld::SetMotorSpeedCommand");
  if (!w_cmd_radps.allFinite()) {
    throw std::invalid_argument("TeamWorld::SetMotorSpeedCommand: non-finite motor speed command");
  }
  w.actuation[static_cast<size_t>(vehicle)].SetCommand(w_cmd_radps);
}

void TeamWorld::ApplyImpulse(int body, const Eigen::Vector3d& impulse_W_Ns, double duration_s) {
  Impl& w = *impl_;
  if (body < -1 || body >= w.n) {
    throw std::out_of_range("TeamWorld::ApplyImpulse: no body " + std::to_string(body));
  }
  if (!impulse_W_Ns.allFinite() || !std::isfinite(duration_s)) {
    throw std::invalid_argument("TeamWorld::ApplyImpulse: non-finite impulse or duration");
  }
  w.disturbances->ApplyImpulse(BodyRef(body), impulse_W_Ns, duration_s);
}

Faults& TeamWorld::faults(int vehicle) {
  impl_->RequireVehicle(vehicle, "TeamWorld::faults");
  return *impl_->faults[static_cast<size_t>(vehicle)];
}

bool TeamWorld::onboard_sensors() const { return impl_->config.onboard_sensors; }

const std::vector<std::unique_ptr<Sensor>>& TeamWorld::sensors(int vehicle) const {
  impl_->RequireVehicle(vehicle, "TeamWorld::sensors");
  static const std::vector<std::unique_ptr<Sensor>> kNone;
  if (impl_->onboard.empty()) return kNone;
  return impl_->onboard[static_cast<size_t>(vehicle)]->sensors();
}

void TeamWorld::TakeDelivered(int vehicle, std::vector<SensorMessage>* out) {
  Impl& w = *impl_;
  w.RequireVehicle(vehicle, "TeamWorld::TakeDelivered");
  if (w.onboard.empty()) {
    out->clear();
    return;
  }
  const size_t v = static_cast<size_t>(vehicle);
  w.onboard[v]->TakeDelivered(w.time_s(), w.faults[v].get(), out);
}

Disturbances& TeamWorld::disturbances() { return *impl_->disturbances; }

void TeamWorld::AddVelocity(int body, const Eigen::Vector3d& dv_W_mps) {
  Impl& w = *impl_;
  if (body < -1 || body >= w.n) {
    throw std::out_of_range("TeamWorld::AddVelocity: no body " + std::to_string(body));
  }
  if (!dv_W_mps.allFinite()) {
    throw std::invalid_argument("TeamWorld::AddVelocity: non-finite velocity change");
  }
  w.disturbances->AddVelocity(BodyRef(body), dv_W_mps);
  mj_forward(w.m, w.d);
  w.CheckWarnings();
}

void TeamWorld::Step() {
  Impl& w = *impl_;
  // the state at t_k the onboard sensors sample (none without them: a team run stays as fast)
  if (!w.onboard.empty()) w.CaptureOnboardState();

  // first-order motor lag, exact for the 1 ms step; thrust to the actuators
  for (Vehicle& v : w.actuation) {
    v.StepMotors();
    v.WriteMotorControls();
  }
  w.disturbances->Apply();

  // dynamics at t_k and integration to t_{k+1}, then kinematics and contacts at t_{k+1} (the
  // single-vehicle World's order: the state, contacts and tendon lengths read after a step
  // belong to the new time; the tension is the force of the step just taken)
  mj_step2(w.m, w.d);
  ++w.step;
  mj_step1(w.m, w.d);
  w.CheckWarnings();

  // the onboard sensors on the step just taken, the others at the new time, then the crash check
  if (!w.onboard.empty()) w.SampleOnboard();
  w.SampleGyros();
  w.SampleMocap();
  w.CheckCrash();
}

double TeamWorld::time_s() const { return impl_->time_s(); }

TeamTruth TeamWorld::GetTruth() const {
  TeamTruth t;
  GetTruth(&t);
  return t;
}

void TeamWorld::GetTruth(TeamTruth* truth) const {
  const Impl& w = *impl_;
  TeamTruth& t = *truth;
  t.time_s = w.time_s();
  t.x.resize(I::Size(w.n));
  t.x.segment<I::kBlockSize>(0) = w.Block(w.payload);
  t.motor_speed_radps.resize(4 * w.n);
  t.cable_length_m.clear();
  t.cable_tension_N.clear();
  t.modes.clear();
  for (int i = 0; i < w.n; ++i) {
    t.x.segment<I::kBlockSize>(I::Vehicle(i)) = w.Block(w.vehicles[i]);
    const double length_m = w.CableLength_m(i);
    t.cable_length_m.push_back(length_m);
    t.cable_tension_N.push_back(w.d->sensordata[w.tension_adr[i]]);
    t.modes.push_back(length_m >= w.config.team.vehicles[i].cable_length_m -
                                      World::kTautLengthTolerance_m
                          ? CableMode::kTaut
                          : CableMode::kSlack);
    t.motor_speed_radps.segment<4>(4 * i) = w.actuation[static_cast<size_t>(i)].motor_speed_radps();
  }
}

std::vector<BodyReading> TeamWorld::TakeDelivered() {
  std::vector<BodyReading> out;
  TakeDelivered(&out);
  return out;
}

void TeamWorld::TakeDelivered(std::vector<BodyReading>* readings) {
  Impl& w = *impl_;
  readings->clear();
  while (std::optional<BodyReading> r = w.mocap_line.PopReady(w.time_s())) {
    readings->push_back(std::move(*r));
  }
}

Eigen::Vector3d TeamWorld::GyroSample_B(int vehicle) const {
  impl_->RequireVehicle(vehicle, "TeamWorld::GyroSample_B");
  return impl_->gyro_B_radps[vehicle];
}

CrashStatus TeamWorld::Crash() const { return impl_->crash; }

double TeamWorld::MinVehicleSeparation_m() const {
  const Impl& w = *impl_;
  double min_m = std::numeric_limits<double>::infinity();
  for (int i = 0; i < w.n; ++i) {
    for (int j = i + 1; j < w.n; ++j) {
      min_m = std::min(
          min_m, (w.Block(w.vehicles[i]).head<3>() - w.Block(w.vehicles[j]).head<3>()).norm());
    }
  }
  return min_m;
}

const CooperativeTeam& TeamWorld::team() const { return impl_->config.team; }

TeamRenderer& TeamWorld::renderer() {
  if (impl_->renderer == nullptr) impl_->renderer = std::make_unique<TeamRenderer>(*this);
  return *impl_->renderer;
}

const mjModel_* TeamWorld::model() const { return impl_->m; }

const mjData_* TeamWorld::data() const { return impl_->d; }

const std::string& TeamWorld::scene_xml() const { return impl_->scene_xml; }

GlBackend TeamWorld::gl_backend() const { return impl_->config.gl_backend; }

}  // namespace hpa::sim
