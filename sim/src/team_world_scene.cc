// TeamWorld's scene: the team's configuration checked, the MJCF built from the single vehicle's
// scene with the team's contact pairs, loaded through MuJoCo's virtual file system, and the ids of
// the elements the world drives.

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "hpa/models/input_error.h"
#include "hpa/sim/cooperative_scene.h"
#include "team_world_impl.h"
#include "world_detail.h"

namespace hpa::sim {

namespace {

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

}  // namespace

void ValidateTeamConfig(const TeamWorldConfig& config) {
  const CooperativeTeam& team = config.team;
  const int n = static_cast<int>(team.vehicles.size());
  if (n < 1 || n > kMaxTeamVehicles) {
    throw InputError("", "team.vehicles",
                     "a team has 1 to " + std::to_string(kMaxTeamVehicles) + " vehicles, got " +
                         std::to_string(n));
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
  if (std::abs(config.rates.physics_hz * World::kPhysicsDt_s - 1.0) > 1e-12) {
    throw InputError(
        "", "rates.physics_hz",
        "must be 1000 Hz (World::kPhysicsDt_s), got " + NumberText(config.rates.physics_hz));
  }
}

std::string TeamBodyName(int body) {
  return body < 0 ? std::string("payload") : "vehicle " + std::to_string(body);
}

void TeamWorld::Impl::LoadScene() {
  // the scene: CooperativeSceneXml plus the contact pairs the crash check needs
  const std::string& file = config.scene_path;
  if (!std::ifstream(file).good()) throw InputError(file, "", "cannot open the MJCF scene file");
  std::string xml;
  try {
    // each vehicle's inertia drawn by the mismatch, one diagonal entry at a time as the single
    // vehicle's, may break the triangle inequality MuJoCo's compiler checks: the scene is
    // compiled with it balanced and the drawn one written into the model after (TeamWorld's
    // constructor), as the single World writes its world's numbers into its loaded model
    CooperativeTeam compiled = config.team;
    for (CooperativeVehicle& v : compiled.vehicles) {
      Eigen::Vector3d& I = v.params.inertia_B_kgm2;
      for (int k = 0; k < 3; ++k) I(k) = std::min(I(k), I((k + 1) % 3) + I((k + 2) % 3));
    }
    xml = SceneWithContactPairs(CooperativeSceneXml(compiled, file), n);
  } catch (const std::runtime_error& e) {
    throw InputError(file, "", std::string("cannot build the team's scene from it: ") + e.what());
  }
  InstallWarningHandler();
  TakeWarnings();
  char error[1024] = "";
  m = LoadXmlText(xml, error, sizeof(error));
  if (m == nullptr) {
    throw InputError(file, "", std::string("MuJoCo cannot load the team's scene: ") + error);
  }
  const std::string load_warnings = TakeWarnings();
  if (!load_warnings.empty() || error[0] != '\0') {
    mj_deleteModel(m);
    m = nullptr;
    throw InputError(file, "",
                     "MuJoCo warning while loading the team's scene: " + load_warnings + error);
  }
  if (std::abs(m->opt.timestep - World::kPhysicsDt_s) > 1e-12) {
    mj_deleteModel(m);
    m = nullptr;
    throw InputError(file, "option.timestep", "must be 0.001 s (World::kPhysicsDt_s)");
  }
  d = mj_makeData(m);
  scene_xml = xml;
}

void TeamWorld::Impl::ResolveIds() {
  const auto free_body = [&](const std::string& body, const std::string& joint) {
    FreeBody b;
    b.body = RequireId(m, mjOBJ_BODY, body);
    const int j = RequireId(m, mjOBJ_JOINT, joint);
    b.qpos = m->jnt_qposadr[j];
    b.dof = m->jnt_dofadr[j];
    return b;
  };
  payload = free_body("payload", "payload_joint");
  payload_geom = RequireId(m, mjOBJ_GEOM, "payload_sphere");
  payload_radius_m = m->geom_size[3 * payload_geom];
  try {
    rotor_radius_m = SingleSceneRotorRadius_m(config.scene_path);
  } catch (const std::runtime_error& e) {
    throw InputError(config.scene_path, "", e.what());
  }
  ground_geom = RequireId(m, mjOBJ_GEOM, "ground");
  for (int i = 0; i < n; ++i) {
    const std::string q = "quadrotor_" + std::to_string(i);
    vehicles.push_back(free_body(q, q + "_joint"));
    box_geom.push_back(RequireId(m, mjOBJ_GEOM, q + "_box"));
    std::array<int, 4> rotors{};
    for (int k = 0; k < 4; ++k) {
      rotors[k] =
          RequireId(m, mjOBJ_ACTUATOR, "rotor_" + std::to_string(i) + "_" + std::to_string(k));
    }
    rotor_actuator.push_back(rotors);
    const int sensor = RequireId(m, mjOBJ_SENSOR, "cable_" + std::to_string(i) + "_tension");
    tension_adr.push_back(m->sensor_adr[sensor]);
  }
}

}  // namespace hpa::sim
