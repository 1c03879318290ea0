// TeamWorld: the MuJoCo world of a team of quadrotors on their own cables carrying one payload
// (docs/cooperative.md), stepped like the single-vehicle World: 1 kHz, first-order motors, the
// same crash conditions and the same MuJoCo warning handling.

#include "hpa/sim/team_world.h"

#include <mujoco/mujoco.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>

#include "hpa/models/input_error.h"
#include "hpa/models/lockstep.h"
#include "hpa/models/rotor_model.h"
#include "hpa/sim/cooperative_scene.h"
#include "world_detail.h"

namespace hpa::sim {

namespace {

using I = CooperativeStateIndex;

// "1.5" for a number in an error message.
std::string NumberText(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

// Throws hpa::InputError naming key unless value is finite and > 0.
void RequirePositive(double value, const std::string& key) {
  if (!(std::isfinite(value) && value > 0.0)) {
    throw InputError("", key, "must be positive and finite, got " + NumberText(value));
  }
}

// Throws hpa::InputError naming key unless value is finite and >= 0.
void RequireNonNegative(double value, const std::string& key) {
  if (!(std::isfinite(value) && value >= 0.0)) {
    throw InputError("", key, "must be zero or positive and finite, got " + NumberText(value));
  }
}

// Bad teams and motion-capture settings, named by their field.
void ValidateConfig(const TeamWorldConfig& config) {
  const CooperativeTeam& team = config.team;
  const int n = static_cast<int>(team.vehicles.size());
  if (n < 1 || n > kMaxTeamVehicles) {
    throw InputError(
        "", "team.vehicles",
        "a team has 1 to " + std::to_string(kMaxTeamVehicles) + " vehicles, got " + std::to_string(n));
  }
  RequirePositive(team.payload_mass_kg, "team.payload_mass_kg");
  for (int k = 0; k < 3; ++k) {
    RequirePositive(team.payload_inertia_P_kgm2(k), "team.payload_inertia_P_kgm2");
  }
  RequirePositive(team.gravity_mps2, "team.gravity_mps2");
  for (int i = 0; i < n; ++i) {
    const CooperativeVehicle& v = team.vehicles[i];
    const std::string key = "team.vehicles[" + std::to_string(i) + "].";
    RequirePositive(v.cable_length_m, key + "cable_length_m");
    RequirePositive(v.params.quad_mass_kg, key + "params.quad_mass_kg");
    for (int k = 0; k < 3; ++k) {
      RequirePositive(v.params.inertia_B_kgm2(k), key + "params.inertia_B_kgm2");
      RequirePositive(v.params.body_half_size_m(k), key + "params.body_half_size_m");
    }
    RequirePositive(v.params.k_f_N_per_radps2, key + "params.k_f_N_per_radps2");
    RequirePositive(v.params.motor_time_constant_s, key + "params.motor_time_constant_s");
    RequirePositive(v.params.motor_speed_max_radps, key + "params.motor_speed_max_radps");
    if (!v.p_PA_P_m.allFinite()) {
      throw InputError("", key + "p_PA_P_m", "must be finite");
    }
  }
  const MocapConfig& m = config.mocap;
  RequirePositive(m.rate_hz, "mocap.rate_hz");
  const double steps_per_sample = 1.0 / (m.rate_hz * World::kPhysicsDt_s);
  if (std::abs(steps_per_sample - std::round(steps_per_sample)) > 1e-9 ||
      std::round(steps_per_sample) < 1.0) {
    throw InputError(
        "", "mocap.rate_hz",
        "must divide the 1000 Hz physics rate into whole steps, got " + NumberText(m.rate_hz));
  }
  RequireNonNegative(m.latency_s, "mocap.latency_s");
  RequireNonNegative(m.position_noise_m, "mocap.position_noise_m");
  RequireNonNegative(m.velocity_noise_mps, "mocap.velocity_noise_mps");
  RequireNonNegative(m.attitude_noise_rad, "mocap.attitude_noise_rad");
  RequireNonNegative(m.rate_gyro_noise_radps, "mocap.rate_gyro_noise_radps");
  RequireNonNegative(m.body_rate_noise_radps, "mocap.body_rate_noise_radps");
}

// The team's scene with explicit contact pairs: the single scene's collision classes keep the
// quadrotor boxes from touching each other and the payload, which the team's crash check needs
// to see. Appended to CooperativeSceneXml's text, which stays as it is for everyone else.
std::string SceneWithContactPairs(const std::string& xml, int n) {
  std::ostringstream pairs;
  pairs << "  <contact>\n";
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      pairs << "    <pair geom1=\"quadrotor_" << i << "_box\" geom2=\"quadrotor_" << j
            << "_box\"/>\n";
    }
    pairs << "    <pair geom1=\"quadrotor_" << i << "_box\" geom2=\"payload_sphere\"/>\n";
  }
  pairs << "  </contact>\n";
  const size_t end = xml.rfind("</mujoco>");
  if (end == std::string::npos) throw std::runtime_error("the team's MJCF has no </mujoco>");
  std::string out = xml;
  out.insert(end, pairs.str());
  return out;
}

// Compiles MJCF text through MuJoCo's virtual file system (mj_loadXML reads files only).
mjModel* LoadXmlText(const std::string& xml, char* error, int error_size) {
  const char* kName = "hpa_team_scene.xml";
  auto vfs = std::make_unique<mjVFS>();  // about 2 MB of fixed tables: not on the stack
  mj_defaultVFS(vfs.get());
  if (mj_makeEmptyFileVFS(vfs.get(), kName, static_cast<int>(xml.size())) != 0) {
    std::snprintf(error, static_cast<size_t>(error_size), "cannot make the in-memory file");
    return nullptr;
  }
  const int file = mj_findFileVFS(vfs.get(), kName);
  std::memcpy(vfs->filedata[file], xml.data(), xml.size());
  mjModel* m = mj_loadXML(kName, vfs.get(), error, error_size);
  mj_deleteVFS(vfs.get());
  return m;
}

// Id of a named element of the team's scene (it is generated, so a miss is a bug, not input).
int RequireId(const mjModel* m, mjtObj type, const std::string& name) {
  const int id = mj_name2id(m, type, name.c_str());
  if (id < 0) throw std::logic_error("the team's scene has no element named " + name);
  return id;
}

// A small rotation of rotation vector r (rad) as a quaternion.
Eigen::Quaterniond RotationOf(const Eigen::Vector3d& r_rad) {
  const double angle_rad = r_rad.norm();
  if (angle_rad == 0.0) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle_rad, r_rad / angle_rad));
}

// Name of a body in crash reasons: "payload" or "vehicle i".
std::string BodyName(int body) {
  return body < 0 ? std::string("payload") : "vehicle " + std::to_string(body);
}

}  // namespace

struct TeamWorld::Impl {
  // where a free body's state lives in MuJoCo
  struct FreeBody {
    int body = -1;  // body id
    int qpos = -1;  // first qpos of its free joint [p, q]
    int dof = -1;   // first dof of its free joint [v (world), w (body)]
  };

  TeamWorldConfig config;
  int n = 0;                   // vehicles
  int mocap_period_steps = 1;  // physics steps between two motion-capture samples
  mjModel* m = nullptr;
  mjData* d = nullptr;
  std::string scene_xml;                   // the MJCF m was compiled from
  std::unique_ptr<TeamRenderer> renderer;  // the video's cameras, made on first use

  FreeBody payload;
  std::vector<FreeBody> vehicles;                  // (n)
  std::vector<std::array<int, 4>> rotor_actuator;  // each vehicle's rotors' actuators (n)
  std::vector<int> box_geom;                       // each vehicle's collision box (n)
  std::vector<int> tension_adr;                    // each cable's tension sensor (n)
  int payload_geom = -1, ground_geom = -1;
  double rotor_radius_m = 0.0;  // the single scene's rotor disc: a rotor's reach beyond its axis

  int64_t step = 0;
  std::mt19937_64 rng;  // all of the world's noise
  std::normal_distribution<double> normal{0.0, 1.0};
  // each vehicle's faults (its motors read them) and its motors and rotors, the single World's
  // components bound to its rotors (n each)
  std::vector<std::unique_ptr<Faults>> faults;
  std::vector<Vehicle> actuation;
  ActuationProfile ideal_actuation;  // a team flies the ideal world: no spread, no battery sag
  double t0_s = 0.0;                 // a team's clock starts at 0 at every Reset
  std::vector<Eigen::Vector3d> gyro_B_radps;     // this step's gyro samples (n x 3)
  DelayLine<BodyReading> mocap_line{0.0};        // readings waiting for their latency
  // a push's constant force on a body until (not including) end_step
  struct TimedForce {
    int body = -1;                                     // MuJoCo body id
    Eigen::Vector3d force_W_N = Eigen::Vector3d::Zero();  // world frame (3)
    int64_t end_step = 0;
  };
  std::vector<TimedForce> forces;  // the pushes not yet over
  CrashStatus crash;
  std::vector<int> warning_count;  // per MuJoCo warning kind (mjNWARNING)

  double time_s() const { return static_cast<double>(step) * World::kPhysicsDt_s; }
  const Params& params(int i) const { return config.team.vehicles[i].params; }

  // three independent standard normal draws
  Eigen::Vector3d Normal3() {
    const double a = normal(rng);
    const double b = normal(rng);
    const double c = normal(rng);
    return Eigen::Vector3d(a, b, c);
  }

  // [p, v, q (w,x,y,z), w_body] of a free body (13)
  Eigen::Matrix<double, 13, 1> Block(const FreeBody& b) const {
    Eigen::Matrix<double, 13, 1> x;
    for (int k = 0; k < 3; ++k) {
      x(k) = d->qpos[b.qpos + k];
      x(3 + k) = d->qvel[b.dof + k];
      x(10 + k) = d->qvel[b.dof + 3 + k];
    }
    for (int k = 0; k < 4; ++k) x(6 + k) = d->qpos[b.qpos + 3 + k];
    return x;
  }

  // writes x's block at `at` into the free body's qpos and qvel (angular velocity in the body
  // frame in both), its quaternion normalised
  void SetBlock(const FreeBody& b, const Eigen::VectorXd& x, int at) {
    const Eigen::Vector4d q = x.segment<4>(at + 6).normalized();
    for (int k = 0; k < 3; ++k) {
      d->qpos[b.qpos + k] = x(at + k);
      d->qvel[b.dof + k] = x(at + 3 + k);
      d->qvel[b.dof + 3 + k] = x(at + 10 + k);
    }
    for (int k = 0; k < 4; ++k) d->qpos[b.qpos + 3 + k] = q(k);
  }

  const FreeBody& Body(int body) const { return body < 0 ? payload : vehicles[body]; }

  // attachment point i in the world (m)
  Eigen::Vector3d AttachPoint_W(int i) const {
    const Eigen::Matrix<double, 13, 1> xp = Block(payload);
    const Eigen::Quaterniond q_WP(xp(6), xp(7), xp(8), xp(9));
    return xp.head<3>() + q_WP.normalized() * config.team.vehicles[i].p_PA_P_m;
  }

  // vehicle i's distance to its attachment point (m)
  double CableLength_m(int i) const {
    return (AttachPoint_W(i) - Block(vehicles[i]).head<3>()).norm();
  }

  bool Taut(int i) const {
    return CableLength_m(i) >=
           config.team.vehicles[i].cable_length_m - World::kTautLengthTolerance_m;
  }

  // Each vehicle's rotor speeds holding its weight and its taut cable's static share of the
  // payload's: the cable tensions T that balance the payload's weight, force and moment about
  // its centre, along the cables as they lie (minimum-norm least squares, negative shares
  // clipped to zero); each vehicle then supplies |m_i g e3 + T_i u_i| (u_i: unit vector from
  // its attachment point to it), shared equally by its four rotors.
  std::vector<InputVector> HoldingSpeeds_radps() const {
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

  // each vehicle's gyro: its true body rate plus white noise
  void SampleGyros() {
    for (int i = 0; i < n; ++i) {
      gyro_B_radps[i] =
          Block(vehicles[i]).segment<3>(10) + config.mocap.rate_gyro_noise_radps * Normal3();
    }
  }

  // the motion-capture readings of this step, if one is due: payload, then each vehicle
  void SampleMocap() {
    if (step % mocap_period_steps != 0) return;
    const MocapConfig& c = config.mocap;
    for (int body = -1; body < n; ++body) {
      const Eigen::Matrix<double, 13, 1> x = Block(Body(body));
      BodyReading r;
      r.body = body;
      r.capture_time_s = time_s();
      r.p_W_m = x.head<3>() + c.position_noise_m * Normal3();
      r.v_W_mps = x.segment<3>(3) + c.velocity_noise_mps * Normal3();
      const Eigen::Quaterniond q_true(x(6), x(7), x(8), x(9));
      r.q_W = (q_true.normalized() * RotationOf(c.attitude_noise_rad * Normal3())).normalized();
      r.w_body_radps = x.segment<3>(10) + c.body_rate_noise_radps * Normal3();
      mocap_line.Push(r.capture_time_s, r);
    }
    // a bound if the caller never takes them: 10 s of readings at 100 Hz
    const size_t max_queued = static_cast<size_t>(1000 * (n + 1));
    while (mocap_line.size() > max_queued) mocap_line.DropOldest();
  }

  // the pushes due this step into xfrc_applied (at the body's centre of mass, world frame); the
  // ones that end with this step are dropped, as Disturbances::Apply drops them
  void ApplyForces() {
    mju_zero(d->xfrc_applied, 6 * m->nbody);
    for (const TimedForce& f : forces) {
      if (step >= f.end_step) continue;
      for (int k = 0; k < 3; ++k) d->xfrc_applied[6 * f.body + k] += f.force_W_N(k);
    }
    forces.erase(std::remove_if(forces.begin(), forces.end(),
                                [this](const TimedForce& f) { return step + 1 >= f.end_step; }),
                 forces.end());
  }


  // a MuJoCo warning is a run error, as in the single-vehicle World
  void CheckWarnings() {
    for (int k = 0; k < mjNWARNING; ++k) {
      const int count = d->warning[k].number;
      if (count == warning_count[k]) continue;
      warning_count[k] = count;
      const std::string text = TakeWarnings();
      if (k == mjWARN_BADQPOS || k == mjWARN_BADQVEL || k == mjWARN_BADQACC) {
        throw std::runtime_error("the team's physics diverged at t = " + std::to_string(time_s()) +
                                 " s (MuJoCo: " + text +
                                 "): the parameters cannot be simulated; a run error, not a crash");
      }
      throw std::runtime_error("MuJoCo warning at t = " + std::to_string(time_s()) + " s: " + text);
    }
  }

  void LatchCrash(const std::string& reason) {
    if (crash.crashed) return;
    crash.crashed = true;
    crash.time_s = time_s();
    crash.reason = reason;
  }

  // vehicle whose box geom g is (-1: none)
  int VehicleOfGeom(int g) const {
    for (int i = 0; i < n; ++i) {
      if (box_geom[i] == g) return i;
    }
    return -1;
  }

  // the crash conditions, the first one met latched
  void CheckCrash() {
    if (crash.crashed) return;
    for (int body = -1; body < n; ++body) {
      if (!Block(Body(body)).allFinite()) return LatchCrash(BodyName(body) + " non-finite state");
    }

    // a vehicle's box touching anything (the payload on the ground is not a crash)
    for (int c = 0; c < d->ncon; ++c) {
      const mjContact& con = d->contact[c];
      const int a = VehicleOfGeom(con.geom1), b = VehicleOfGeom(con.geom2);
      if (a < 0 && b < 0) continue;
      if (a >= 0 && b >= 0) {
        return LatchCrash("vehicle " + std::to_string(std::min(a, b)) + " and vehicle " +
                          std::to_string(std::max(a, b)) + " collide");
      }
      const int vehicle = a >= 0 ? a : b;
      const int other = a >= 0 ? con.geom2 : con.geom1;
      std::string what;
      if (other == ground_geom) {
        what = "ground";
      } else if (other == payload_geom) {
        what = "payload";
      } else {
        const char* name = mj_id2name(m, mjOBJ_GEOM, other);
        what = name ? name : "a geom";
      }
      return LatchCrash(BodyName(vehicle) + " contact with " + what);
    }

    // a cable through another vehicle's rotors: MuJoCo's tendons have no contact geometry, so
    // each cable (a straight segment while it is taut, the only time it can cut) is checked
    // against every other vehicle's rotor disc, a flat cylinder of the vehicle's reach in its
    // body's x-y plane; a strike is a crash, as a cable caught in a propeller is
    for (int i = 0; i < n; ++i) {
      if (!Taut(i)) continue;
      const Eigen::Vector3d a_W = Block(vehicles[i]).head<3>();
      const Eigen::Vector3d b_W = AttachPoint_W(i);
      for (int j = 0; j < n; ++j) {
        if (j == i) continue;
        const Eigen::Matrix<double, 13, 1> x = Block(vehicles[j]);
        const Eigen::Quaterniond q_WB = Eigen::Quaterniond(x(6), x(7), x(8), x(9)).normalized();
        const double reach_m = params(j).arm_length_m + rotor_radius_m;
        const double half_height_m = params(j).body_half_size_m.z();
        // samples no farther apart than the disc's half thickness: a crossing is never missed
        const int samples = static_cast<int>(std::ceil((b_W - a_W).norm() / half_height_m));
        for (int k = 0; k <= samples; ++k) {
          const Eigen::Vector3d p_B =
              q_WB.conjugate() * (a_W + (b_W - a_W) * k / samples - x.head<3>());
          if (std::abs(p_B.z()) <= half_height_m && p_B.head<2>().norm() <= reach_m) {
            return LatchCrash("cable " + std::to_string(i) + " strikes " + BodyName(j) +
                              "'s rotors");
          }
        }
      }
    }

    // a vehicle's tilt past 90 deg: its body z below the horizon
    for (int i = 0; i < n; ++i) {
      const Eigen::Matrix<double, 13, 1> x = Block(vehicles[i]);
      const Eigen::Quaterniond q_WB(x(6), x(7), x(8), x(9));
      if (q_WB.normalized().toRotationMatrix()(2, 2) < 0.0) {
        return LatchCrash(BodyName(i) + " tilt > 90 deg");
      }
    }

    // any body outside the arena (kArenaHalfWidth_m, kArenaHeight_m)
    for (int body = -1; body < n; ++body) {
      const Eigen::Vector3d p = Block(Body(body)).head<3>();
      if (std::abs(p.x()) > kArenaHalfWidth_m || std::abs(p.y()) > kArenaHalfWidth_m ||
          p.z() < 0.0 || p.z() > kArenaHeight_m) {
        return LatchCrash(BodyName(body) + " left the 20x20x10 m arena");
      }
    }
  }
};

TeamWorld::TeamWorld(const TeamWorldConfig& config) : impl_(std::make_unique<Impl>()) {
  Impl& w = *impl_;
  ValidateConfig(config);
  w.config = config;
  w.n = static_cast<int>(config.team.vehicles.size());
  w.mocap_period_steps =
      static_cast<int>(std::lround(1.0 / (config.mocap.rate_hz * World::kPhysicsDt_s)));
  w.mocap_line = DelayLine<BodyReading>(config.mocap.latency_s);

  // the scene: CooperativeSceneXml plus the contact pairs the crash check needs
  const std::string& file = config.scene_path;
  if (!std::ifstream(file).good()) throw InputError(file, "", "cannot open the MJCF scene file");
  std::string xml;
  try {
    xml = SceneWithContactPairs(CooperativeSceneXml(config.team, file), w.n);
  } catch (const std::runtime_error& e) {
    throw InputError(file, "", std::string("cannot build the team's scene from it: ") + e.what());
  }
  InstallWarningHandler();
  TakeWarnings();
  char error[1024] = "";
  w.m = LoadXmlText(xml, error, sizeof(error));
  if (w.m == nullptr) {
    throw InputError(file, "", std::string("MuJoCo cannot load the team's scene: ") + error);
  }
  const std::string load_warnings = TakeWarnings();
  if (!load_warnings.empty() || error[0] != '\0') {
    mj_deleteModel(w.m);
    w.m = nullptr;
    throw InputError(file, "",
                     "MuJoCo warning while loading the team's scene: " + load_warnings + error);
  }
  if (std::abs(w.m->opt.timestep - World::kPhysicsDt_s) > 1e-12) {
    mj_deleteModel(w.m);
    w.m = nullptr;
    throw InputError(file, "option.timestep", "must be 0.001 s (World::kPhysicsDt_s)");
  }
  w.d = mj_makeData(w.m);
  w.scene_xml = xml;

  // the elements the world drives
  const auto free_body = [&](const std::string& body, const std::string& joint) {
    Impl::FreeBody b;
    b.body = RequireId(w.m, mjOBJ_BODY, body);
    const int j = RequireId(w.m, mjOBJ_JOINT, joint);
    b.qpos = w.m->jnt_qposadr[j];
    b.dof = w.m->jnt_dofadr[j];
    return b;
  };
  w.payload = free_body("payload", "payload_joint");
  w.payload_geom = RequireId(w.m, mjOBJ_GEOM, "payload_sphere");
  try {
    w.rotor_radius_m = SingleSceneRotorRadius_m(config.scene_path);
  } catch (const std::runtime_error& e) {
    throw InputError(config.scene_path, "", e.what());
  }
  w.ground_geom = RequireId(w.m, mjOBJ_GEOM, "ground");
  for (int i = 0; i < w.n; ++i) {
    const std::string q = "quadrotor_" + std::to_string(i);
    w.vehicles.push_back(free_body(q, q + "_joint"));
    w.box_geom.push_back(RequireId(w.m, mjOBJ_GEOM, q + "_box"));
    std::array<int, 4> rotors{};
    for (int k = 0; k < 4; ++k) {
      rotors[k] =
          RequireId(w.m, mjOBJ_ACTUATOR, "rotor_" + std::to_string(i) + "_" + std::to_string(k));
    }
    w.rotor_actuator.push_back(rotors);
    const int sensor = RequireId(w.m, mjOBJ_SENSOR, "cable_" + std::to_string(i) + "_tension");
    w.tension_adr.push_back(w.m->sensor_adr[sensor]);
  }
  for (int i = 0; i < w.n; ++i) {
    w.faults.push_back(std::make_unique<Faults>(config.seed));
    VehicleBinding binding;
    binding.model = w.m;
    binding.data = w.d;
    binding.rotor_actuator = w.rotor_actuator[static_cast<size_t>(i)];
    binding.params = &w.params(i);
    binding.actuation = &w.ideal_actuation;
    binding.faults = w.faults.back().get();
    binding.step = &w.step;
    binding.t0_s = &w.t0_s;
    w.actuation.emplace_back(binding);
  }
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
  w.forces.clear();
  for (const std::unique_ptr<Faults>& f : w.faults) f->Clear();
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
  if (vehicle < 0 || vehicle >= w.n) {
    throw std::out_of_range("TeamWorld::SetMotorSpeedCommand: no vehicle " +
                            std::to_string(vehicle));
  }
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
  const int64_t steps = std::max<int64_t>(1, std::llround(duration_s / World::kPhysicsDt_s));
  w.forces.push_back(
      {w.Body(body).body, impulse_W_Ns / (static_cast<double>(steps) * World::kPhysicsDt_s),
       w.step + steps});
}

Faults& TeamWorld::faults(int vehicle) {
  Impl& w = *impl_;
  if (vehicle < 0 || vehicle >= w.n) {
    throw std::out_of_range("TeamWorld::faults: no vehicle " + std::to_string(vehicle));
  }
  return *w.faults[static_cast<size_t>(vehicle)];
}

void TeamWorld::AddVelocity(int body, const Eigen::Vector3d& dv_W_mps) {
  Impl& w = *impl_;
  if (body < -1 || body >= w.n) {
    throw std::out_of_range("TeamWorld::AddVelocity: no body " + std::to_string(body));
  }
  if (!dv_W_mps.allFinite()) {
    throw std::invalid_argument("TeamWorld::AddVelocity: non-finite velocity change");
  }
  const Impl::FreeBody& b = w.Body(body);
  for (int k = 0; k < 3; ++k) w.d->qvel[b.dof + k] += dv_W_mps(k);
  mj_forward(w.m, w.d);
  w.CheckWarnings();
}

void TeamWorld::Step() {
  Impl& w = *impl_;
  // first-order motor lag, exact for the 1 ms step; thrust to the actuators
  for (Vehicle& v : w.actuation) {
    v.StepMotors();
    v.WriteMotorControls();
  }
  w.ApplyForces();

  // dynamics at t_k and integration to t_{k+1}, then kinematics and contacts at t_{k+1} (the
  // single-vehicle World's order: the state, contacts and tendon lengths read after a step
  // belong to the new time; the tension is the force of the step just taken)
  mj_step2(w.m, w.d);
  ++w.step;
  mj_step1(w.m, w.d);
  w.CheckWarnings();

  // sensors at the new time, then the crash check
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
  if (vehicle < 0 || vehicle >= impl_->n) {
    throw std::out_of_range("TeamWorld::GyroSample_B: no vehicle " + std::to_string(vehicle));
  }
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
