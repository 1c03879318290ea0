#include "hpa/models/params.h"

#include <Eigen/LU>
#include <cmath>
#include <cstdio>

#include "hpa/models/data_dir.h"
#include "hpa/models/input_error.h"
#include "hpa/models/params_yaml.h"
#include "hpa/models/yaml_reader.h"

namespace hpa {

double Params::HoverMotorSpeedRadps() const {
  return std::sqrt(HoverThrustN() / (4.0 * k_f_N_per_radps2));
}

double Params::CameraFocalPx() const {
  return 0.5 * camera_height_px / std::tan(0.5 * camera_fovy_deg * M_PI / 180.0);
}

std::string DefaultParamsPath() { return DataPath("models/params.yaml"); }

Params LoadParams(const std::string& path) { return ParseParams(YamlMap::LoadFile(path)); }

namespace {

// A number as %g writes it (0.5, 1830, 2.4e+04), for messages.
std::string Short(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// Copies every key of `from` into `into`, descending into maps both have.
void MergeInto(YAML::Node into, const YAML::Node& from) {
  for (const auto& kv : from) {
    const std::string key = kv.first.as<std::string>();
    if (kv.second.IsMap() && into[key] && into[key].IsMap()) {
      MergeInto(into[key], kv.second);
    } else {
      into[key] = YAML::Clone(kv.second);
    }
  }
}

YAML::Node Seq(const double* v, int n) {
  YAML::Node s(YAML::NodeType::Sequence);
  for (int i = 0; i < n; ++i) s.push_back(v[i]);
  return s;
}

}  // namespace

YAML::Node ParamsToYaml(const Params& p) {
  YAML::Node n;
  n["gravity_mps2"] = p.gravity_mps2;
  n["quadrotor"]["mass_kg"] = p.quad_mass_kg;
  n["quadrotor"]["inertia_kgm2"] = Seq(p.inertia_B_kgm2.data(), 3);
  n["quadrotor"]["arm_length_m"] = p.arm_length_m;
  n["quadrotor"]["body_half_size_m"] = Seq(p.body_half_size_m.data(), 3);
  n["rotor"]["k_f_N_per_radps2"] = p.k_f_N_per_radps2;
  n["rotor"]["k_m_Nm_per_radps2"] = p.k_m_Nm_per_radps2;
  n["rotor"]["motor_time_constant_s"] = p.motor_time_constant_s;
  n["rotor"]["motor_speed_min_radps"] = p.motor_speed_min_radps;
  n["rotor"]["motor_speed_max_radps"] = p.motor_speed_max_radps;
  n["payload"]["mass_kg"] = p.payload_mass_kg;
  n["payload"]["radius_m"] = p.payload_radius_m;
  n["cable"]["length_m"] = p.cable_length_m;
  n["cable"]["slack_epsilon_m"] = p.slack_epsilon_m;
  YAML::Node cam = n["payload_camera"];
  cam["width_px"] = p.camera_width_px;
  cam["height_px"] = p.camera_height_px;
  cam["fovy_deg"] = p.camera_fovy_deg;
  cam["t_BC_B_m"] = Seq(p.t_BC_B_m.data(), 3);
  YAML::Node r(YAML::NodeType::Sequence);
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d row = p.R_BC.row(i).transpose();
    r.push_back(Seq(row.data(), 3));
  }
  cam["R_BC"] = r;
  cam["distortion_k1_k2_p1_p2"] = Seq(p.camera_distortion.data(), 4);
  n["vio_camera"]["width_px"] = p.vio_width_px;
  n["vio_camera"]["height_px"] = p.vio_height_px;
  return n;
}

Params ParamsWithOverrides(const Params& base, const YAML::Node& overrides,
                           const std::string& file) {
  if (!overrides.IsMap()) {
    throw InputError(file, "params",
                     "expected a map shaped like params.yaml, e.g. "
                     "{cable: {length_m: 0.8}}");
  }
  YAML::Node merged = ParamsToYaml(base);
  MergeInto(merged, overrides);
  return ParseParams(YamlMap(merged, file, "params"));
}

Params ParseParams(const YamlMap& root) {
  Params p;
  p.gravity_mps2 = root.Number("gravity_mps2", 0.1, 100.0);

  const YamlMap quad = root.Map("quadrotor");
  p.quad_mass_kg = quad.Number("mass_kg", 0.01, 100.0);
  p.inertia_B_kgm2 = quad.Vector("inertia_kgm2", 3, 1e-6, 10.0);
  p.arm_length_m = quad.Number("arm_length_m", 0.01, 5.0);
  p.body_half_size_m = quad.Vector("body_half_size_m", 3, 1e-3, 5.0);
  quad.RejectUnknownKeys();

  const YamlMap rotor = root.Map("rotor");
  p.k_f_N_per_radps2 = rotor.Number("k_f_N_per_radps2", 1e-12, 1.0);
  p.k_m_Nm_per_radps2 = rotor.Number("k_m_Nm_per_radps2", 1e-14, 1.0);
  // a propeller's torque-to-thrust ratio k_m / k_f is a length of the order of a tenth of its
  // radius (0.01-0.05 m for 5-10 inch propellers; 0.016 m here): 0.2 m is no propeller, and
  // MuJoCo cannot integrate the yaw such a ratio gives
  if (p.k_m_Nm_per_radps2 / p.k_f_N_per_radps2 > 0.2) {
    rotor.Fail("k_m_Nm_per_radps2",
               "k_m / k_f (k_m_Nm_per_radps2 / k_f_N_per_radps2) is " +
                   Short(p.k_m_Nm_per_radps2 / p.k_f_N_per_radps2) +
                   " m: expected at most 0.2 m (a real propeller's is 0.01-0.05 m)");
  }
  p.motor_time_constant_s = rotor.Number("motor_time_constant_s", 1e-4, 1.0);
  p.motor_speed_min_radps = rotor.Number("motor_speed_min_radps", 0.0, 1e5);
  p.motor_speed_max_radps = rotor.Number("motor_speed_max_radps", 1.0, 1e5);
  if (p.motor_speed_max_radps <= p.motor_speed_min_radps) {
    rotor.Fail("motor_speed_min_radps",
               "must be below motor_speed_max_radps (" + Short(p.motor_speed_max_radps) + ")");
  }
  rotor.RejectUnknownKeys();

  const YamlMap payload = root.Map("payload");
  p.payload_mass_kg = payload.Number("mass_kg", 1e-3, 100.0);
  p.payload_radius_m = payload.Number("radius_m", 1e-3, 1.0);
  payload.RejectUnknownKeys();

  const YamlMap cable = root.Map("cable");
  p.cable_length_m = cable.Number("length_m", 0.05, 10.0);
  p.slack_epsilon_m = cable.Number("slack_epsilon_m", 0.0, 1.0);
  if (!(p.slack_epsilon_m < p.cable_length_m)) {
    cable.Fail("slack_epsilon_m", "must be below the cable's length_m (" + Short(p.cable_length_m) +
                                      "): slack is a distance shorter than the cable by it");
  }
  cable.RejectUnknownKeys();

  const YamlMap cam = root.Map("payload_camera");
  p.camera_width_px = static_cast<int>(cam.Integer("width_px", 16, 8192));
  p.camera_height_px = static_cast<int>(cam.Integer("height_px", 16, 8192));
  p.camera_fovy_deg = cam.Number("fovy_deg", 1.0, 170.0);
  p.t_BC_B_m = cam.Vector("t_BC_B_m", 3, -5.0, 5.0);
  if (cam.Has("distortion_k1_k2_p1_p2")) {
    p.camera_distortion = cam.Vector("distortion_k1_k2_p1_p2", 4, -2.0, 2.0);
  }
  const YAML::Node r = cam.Node("R_BC");
  const std::string r_expect = "expected a 3x3 rotation matrix as a list of 3 rows";
  if (!r.IsSequence() || r.size() != 3) cam.Fail("R_BC", r_expect);
  for (int i = 0; i < 3; ++i) {
    if (!r[i].IsSequence() || r[i].size() != 3) cam.Fail("R_BC", r_expect);
    for (int j = 0; j < 3; ++j) {
      try {
        p.R_BC(i, j) = r[i][j].as<double>();
      } catch (const YAML::Exception&) {
        cam.Fail("R_BC", r_expect);
      }
    }
  }
  if (!(p.R_BC.transpose() * p.R_BC).isIdentity(1e-9) ||
      std::abs(p.R_BC.determinant() - 1) > 1e-9) {
    cam.Fail("R_BC", "not a rotation (R^T R != I or det != 1)");
  }
  cam.RejectUnknownKeys();

  const YamlMap vio = root.Map("vio_camera");
  p.vio_width_px = static_cast<int>(vio.Integer("width_px", 16, 8192));
  p.vio_height_px = static_cast<int>(vio.Integer("height_px", 16, 8192));
  vio.RejectUnknownKeys();

  root.RejectUnknownKeys();
  return p;
}

}  // namespace hpa
