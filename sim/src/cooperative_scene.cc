#include "hpa/sim/cooperative_scene.h"

#include <mujoco/mujoco.h>

#include <cmath>
#include <iomanip>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "hpa/models/rotor_model.h"

namespace hpa::sim {
namespace {

// What the cooperative scene takes from the single-vehicle scene: the world, the cable's
// limit settings and the bodies' collision classes.
struct SingleSceneSettings {
  double timestep_s = 0;
  Eigen::Vector3d gravity_W_mps2 = Eigen::Vector3d::Zero();  // (3)
  double cable_solref_lim[mjNREF] = {};                      // (timeconst, dampratio)
  double cable_solimp_lim[mjNIMP] = {};                      // (dmin, dmax, width, mid, power)
  double cable_width_m = 0;
  int quad_contype = 0, quad_conaffinity = 0;        // the quadrotor box
  int payload_contype = 0, payload_conaffinity = 0;  // the payload sphere
};

// Id of a named element of the single-vehicle scene; throws naming it if it is missing.
int RequireId(const mjModel* m, mjtObj type, const char* name, const std::string& path) {
  const int id = mj_name2id(m, type, name);
  if (id < 0) throw std::runtime_error(path + ": no element named " + name);
  return id;
}

// The single-vehicle scene compiled; throws naming it if MuJoCo cannot load it.
std::unique_ptr<mjModel, void (*)(mjModel*)> LoadSingleScene(const std::string& path) {
  char error[1024] = "";
  std::unique_ptr<mjModel, void (*)(mjModel*)> m(
      mj_loadXML(path.c_str(), nullptr, error, sizeof(error)), mj_deleteModel);
  if (m == nullptr) throw std::runtime_error(path + ": MuJoCo cannot load it: " + error);
  return m;
}

SingleSceneSettings ReadSingleScene(const std::string& path) {
  const std::unique_ptr<mjModel, void (*)(mjModel*)> m = LoadSingleScene(path);
  SingleSceneSettings s;
  s.timestep_s = m->opt.timestep;
  s.gravity_W_mps2 = Eigen::Vector3d(m->opt.gravity[0], m->opt.gravity[1], m->opt.gravity[2]);
  const int cable = RequireId(m.get(), mjOBJ_TENDON, "cable", path);
  for (int k = 0; k < mjNREF; ++k) s.cable_solref_lim[k] = m->tendon_solref_lim[mjNREF * cable + k];
  for (int k = 0; k < mjNIMP; ++k) s.cable_solimp_lim[k] = m->tendon_solimp_lim[mjNIMP * cable + k];
  s.cable_width_m = m->tendon_width[cable];
  const int box = RequireId(m.get(), mjOBJ_GEOM, "quadrotor_box", path);
  s.quad_contype = m->geom_contype[box];
  s.quad_conaffinity = m->geom_conaffinity[box];
  const int sphere = RequireId(m.get(), mjOBJ_GEOM, "payload_sphere", path);
  s.payload_contype = m->geom_contype[sphere];
  s.payload_conaffinity = m->geom_conaffinity[sphere];
  return s;
}

// "x y z" of a vector.
std::string Triple(const Eigen::Vector3d& v) {
  std::ostringstream out;
  out << std::setprecision(17) << v.x() << ' ' << v.y() << ' ' << v.z();
  return out.str();
}

}  // namespace

double SingleSceneRotorRadius_m(const std::string& single_scene_path) {
  const std::unique_ptr<mjModel, void (*)(mjModel*)> m = LoadSingleScene(single_scene_path);
  return m->geom_size[3 * RequireId(m.get(), mjOBJ_GEOM, "rotor0_disc", single_scene_path)];
}

namespace {

// The payload: a rigid body with the team's mass and inertia, one site per attachment point.
void WritePayload(const CooperativeTeam& team, const SingleSceneSettings& s, std::ostream* out) {
  std::ostream& x = *out;
  const int n = static_cast<int>(team.vehicles.size());
  const double payload_radius_m = team.vehicles.front().params.payload_radius_m;
  x << "    <body name=\"payload\" pos=\"0 0 0.5\">\n"
    << "      <freejoint name=\"payload_joint\"/>\n"
    << "      <inertial pos=\"0 0 0\" mass=\"" << team.payload_mass_kg << "\" diaginertia=\""
    << Triple(team.payload_inertia_P_kgm2) << "\"/>\n"
    << "      <geom name=\"payload_sphere\" type=\"sphere\" size=\"" << payload_radius_m
    << "\" rgba=\"0.85 0.05 0.04 1\" contype=\"" << s.payload_contype << "\" conaffinity=\""
    << s.payload_conaffinity << "\"/>\n";
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& rho = team.vehicles[i].p_PA_P_m;
    x << "      <site name=\"attach_" << i << "\" pos=\"" << Triple(rho) << "\" size=\"0.005\"/>\n";
    if (rho.norm() > payload_radius_m) {  // a visual-only strut from the centre to the point
      x << "      <geom type=\"capsule\" fromto=\"0 0 0 " << Triple(rho)
        << "\" size=\"0.01\" rgba=\"0.85 0.05 0.04 1\" contype=\"0\" conaffinity=\"0\" "
           "group=\"1\"/>\n";
    }
  }
  x << "    </body>\n";
}

// The vehicles: models/scene.xml's quadrotor, numbers from each vehicle's params.
void WriteVehicles(const CooperativeTeam& team, const SingleSceneSettings& s, std::ostream* out) {
  std::ostream& x = *out;
  const int n = static_cast<int>(team.vehicles.size());
  for (int i = 0; i < n; ++i) {
    const CooperativeVehicle& v = team.vehicles[i];
    const Params& p = v.params;
    const Eigen::Vector3d p_start =
        Eigen::Vector3d(0, 0, 0.5) + v.p_PA_P_m + Eigen::Vector3d(0, 0, v.cable_length_m);
    x << "    <body name=\"quadrotor_" << i << "\" pos=\"" << Triple(p_start) << "\">\n"
      << "      <freejoint name=\"quadrotor_" << i << "_joint\"/>\n"
      << "      <inertial pos=\"0 0 0\" mass=\"" << p.quad_mass_kg << "\" diaginertia=\""
      << Triple(p.inertia_B_kgm2) << "\"/>\n"
      << "      <geom name=\"quadrotor_" << i << "_box\" type=\"box\" size=\""
      << Triple(p.body_half_size_m) << "\" rgba=\"0.15 0.15 0.18 1\" contype=\"" << s.quad_contype
      << "\" conaffinity=\"" << s.quad_conaffinity << "\"/>\n";
    for (int k = 0; k < 4; ++k) {
      x << "      <site name=\"rotor_" << i << "_" << k << "\" pos=\""
        << Triple(RotorPosition_B(p, k)) << "\" size=\"0.01\"/>\n";
    }
    x << "      <site name=\"cable_quadrotor_" << i << "\" pos=\"0 0 0\" size=\"0.005\"/>\n"
      << "    </body>\n";
  }
}

// The cables: the single-vehicle cable's limit settings, each at its own length.
void WriteCables(const CooperativeTeam& team, const SingleSceneSettings& s, std::ostream* out) {
  std::ostream& x = *out;
  const int n = static_cast<int>(team.vehicles.size());
  x << "  <tendon>\n";
  for (int i = 0; i < n; ++i) {
    x << "    <spatial name=\"cable_" << i << "\" limited=\"true\" range=\"0 "
      << team.vehicles[i].cable_length_m << "\" width=\"" << s.cable_width_m
      << "\" rgba=\"0.1 0.1 0.1 1\" solreflimit=\"" << s.cable_solref_lim[0] << ' '
      << s.cable_solref_lim[1] << "\" solimplimit=\"";
    for (int k = 0; k < mjNIMP; ++k) x << (k ? " " : "") << s.cable_solimp_lim[k];
    x << "\">\n"
      << "      <site site=\"cable_quadrotor_" << i << "\"/>\n"
      << "      <site site=\"attach_" << i << "\"/>\n"
      << "    </spatial>\n";
  }
  x << "  </tendon>\n";
}

// The rotors (ctrl = thrust (N) within the motors' range, yaw gear spin * k_m / k_f) and each
// cable's tension sensor.
void WriteActuatorsAndSensors(const CooperativeTeam& team, std::ostream* out) {
  std::ostream& x = *out;
  const int n = static_cast<int>(team.vehicles.size());
  x << "  <actuator>\n";
  for (int i = 0; i < n; ++i) {
    const Params& p = team.vehicles[i].params;
    const double f_min_N = p.RotorThrustMinN();
    const double f_max_N = p.RotorThrustMaxN();
    for (int k = 0; k < 4; ++k) {
      x << "    <general name=\"rotor_" << i << "_" << k << "\" site=\"rotor_" << i << "_" << k
        << "\" gear=\"0 0 1 0 0 " << RotorSpin(k) * p.k_m_Nm_per_radps2 / p.k_f_N_per_radps2
        << "\" ctrllimited=\"true\" ctrlrange=\"" << f_min_N << ' ' << f_max_N << "\"/>\n";
    }
  }
  x << "  </actuator>\n"
    << "  <sensor>\n";
  for (int i = 0; i < n; ++i) {
    x << "    <tendonlimitfrc name=\"cable_" << i << "_tension\" tendon=\"cable_" << i << "\"/>\n";
  }
  x << "  </sensor>\n"
    << "</mujoco>\n";
}

}  // namespace

std::string CooperativeSceneXml(const CooperativeTeam& team, const std::string& single_scene_path) {
  const SingleSceneSettings s = ReadSingleScene(single_scene_path);
  const int n = static_cast<int>(team.vehicles.size());
  std::ostringstream x;
  x << std::setprecision(17);
  x << "<mujoco model=\"hpa_cooperative_" << n << "\">\n"
    << "  <compiler angle=\"radian\" coordinate=\"local\" inertiafromgeom=\"false\"/>\n"
    << "  <option timestep=\"" << s.timestep_s << "\" gravity=\"" << Triple(s.gravity_W_mps2)
    << "\" integrator=\"Euler\" cone=\"pyramidal\"/>\n"
    << "  <size njmax=\"" << 100 * (n + 1) << "\" nconmax=\"" << 25 * (n + 1) << "\"/>\n"
    << "  <worldbody>\n"
    << "    <geom name=\"ground\" type=\"plane\" size=\"10 10 1\" contype=\"1\" "
       "conaffinity=\"1\"/>\n";

  WritePayload(team, s, &x);
  WriteVehicles(team, s, &x);
  x << "  </worldbody>\n";
  WriteCables(team, s, &x);
  WriteActuatorsAndSensors(team, &x);
  return x.str();
}

}  // namespace hpa::sim
