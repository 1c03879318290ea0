#include "hpa/models/params.h"

#include <Eigen/LU>
#include <cmath>
#include <cstdio>

#include "hpa/models/data_dir.h"
#include "hpa/models/input_error.h"
#include "hpa/models/param_yaml.h"
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

const std::vector<ParamTable<Params>>& ParamsTables() {
  using P = Params;
  static const std::vector<ParamTable<P>> tables = {
      {"",
       "top-level keys",
       {{"gravity_mps2", "m/s^2", 0.1, 100.0, "gravitational acceleration, z up",
         &P::gravity_mps2}}},
      {"quadrotor",
       "the vehicle's rigid body",
       {{"mass_kg", "kg", 0.01, 100.0, "quadrotor mass", &P::quad_mass_kg, "quad_mass_kg"},
        {"inertia_kgm2", "kg m^2", 1e-6, 10.0, "diagonal of the body inertia J", &P::inertia_B_kgm2,
         "inertia_B_kgm2"},
        {"arm_length_m", "m", 0.01, 5.0, "centre to rotor axis, X configuration", &P::arm_length_m},
        {"body_half_size_m", "m", 1e-3, 5.0, "collision box half sizes (crash detection)",
         &P::body_half_size_m}}},
      {"rotor",
       "the four rotors and motors",
       {{"k_f_N_per_radps2", "N/(rad/s)^2", 1e-12, 1.0, "thrust f_i = k_f w_i^2",
         &P::k_f_N_per_radps2},
        {"k_m_Nm_per_radps2", "N m/(rad/s)^2", 1e-14, 1.0,
         "yaw reaction torque tau_i = k_m w_i^2 (k_m / k_f at most 0.2 m)", &P::k_m_Nm_per_radps2},
        {"motor_time_constant_s", "s", 1e-4, 1.0, "first-order motor spin-up",
         &P::motor_time_constant_s},
        {"motor_speed_min_radps", "rad/s", 0.0, 1e5, "idle speed (below the maximum)",
         &P::motor_speed_min_radps},
        {"motor_speed_max_radps", "rad/s", 1.0, 1e5, "full speed", &P::motor_speed_max_radps}}},
      {"payload",
       "the sphere on the cable",
       {{"mass_kg", "kg", 1e-3, 100.0, "payload mass", &P::payload_mass_kg, "payload_mass_kg"},
        {"radius_m", "m", 1e-3, 1.0, "payload sphere radius", &P::payload_radius_m,
         "payload_radius_m"}}},
      {"cable",
       "the massless cable",
       {{"length_m", "m", 0.05, 10.0, "cable length l", &P::cable_length_m, "cable_length_m"},
        {"slack_epsilon_m", "m", 0.0, 1.0,
         "slack when the filtered length is below l - epsilon (below l)", &P::slack_epsilon_m}}},
      {"payload_camera",
       "the downward camera that sees the payload",
       {{"width_px", "px", 16, 8192, "image width", &P::camera_width_px, "camera_width_px"},
        {"height_px", "px", 16, 8192, "image height", &P::camera_height_px, "camera_height_px"},
        {"fovy_deg", "deg", 1.0, 170.0, "vertical field of view", &P::camera_fovy_deg,
         "camera_fovy_deg"},
        {"t_BC_B_m", "m", -5.0, 5.0, "camera origin in the body frame", &P::t_BC_B_m},
        {"R_BC", "-", -1.0, 1.0, "camera axes in the body frame (a rotation, rows)", &P::R_BC,
         "R_BC_rowmajor"},
        {"distortion_k1_k2_p1_p2", "-", -2.0, 2.0,
         "radial-tangential lens distortion on normalised coordinates (zero: pinhole)",
         &P::camera_distortion, "camera_distortion"}}},
      {"vio_camera",
       "the VIO camera (a noisy, delayed pose stream)",
       {{"width_px", "px", 16, 8192, "image width", &P::vio_width_px, "vio_width_px"},
        {"height_px", "px", 16, 8192, "image height", &P::vio_height_px, "vio_height_px"}}},
  };
  return tables;
}

YAML::Node ParamsToYaml(const Params& p) {
  YAML::Node n(YAML::NodeType::Map);  // a map already, so that `section` below shares it
  for (const ParamTable<Params>& table : ParamsTables()) {
    YAML::Node section = table.section.empty() ? n : n[table.section];
    for (const ParamDecl<Params>& d : table.params) {
      std::visit(
          [&](auto member) {
            using T = std::decay_t<decltype(p.*member)>;
            if constexpr (std::is_same_v<T, Eigen::Matrix3d>) {
              YAML::Node rows(YAML::NodeType::Sequence);
              for (int i = 0; i < 3; ++i) {
                const Eigen::Vector3d row = (p.*member).row(i).transpose();
                rows.push_back(Seq(row.data(), 3));
              }
              section[d.key] = rows;
            } else if constexpr (std::is_same_v<T, double> || std::is_same_v<T, int> ||
                                 std::is_same_v<T, bool>) {
              section[d.key] = p.*member;
            } else {
              section[d.key] = Seq((p.*member).data(), static_cast<int>(T::RowsAtCompileTime));
            }
          },
          d.member);
    }
  }
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
  for (const ParamTable<Params>& table : ParamsTables()) {
    if (table.section.empty()) {
      // the top-level keys: read here, the unknown ones refused with the sections below
      for (const ParamDecl<Params>& d : table.params) {
        p.*std::get<double Params::*>(d.member) = root.Number(d.key, d.min, d.max);
      }
      continue;
    }
    ReadParamTable(root.Map(table.section), table, &p, /*required=*/true);
  }
  // what no single range says
  const YamlMap rotor(root.Node("rotor"), root.file(), root.KeyPath("rotor"));
  // a propeller's torque-to-thrust ratio k_m / k_f is a length of the order of a tenth of its
  // radius (0.01-0.05 m for 5-10 inch propellers; 0.016 m here): 0.2 m is no propeller, and
  // MuJoCo cannot integrate the yaw such a ratio gives
  if (p.k_m_Nm_per_radps2 / p.k_f_N_per_radps2 > 0.2) {
    rotor.Fail("k_m_Nm_per_radps2",
               "k_m / k_f (k_m_Nm_per_radps2 / k_f_N_per_radps2) is " +
                   Short(p.k_m_Nm_per_radps2 / p.k_f_N_per_radps2) +
                   " m: expected at most 0.2 m (a real propeller's is 0.01-0.05 m)");
  }
  if (p.motor_speed_max_radps <= p.motor_speed_min_radps) {
    rotor.Fail("motor_speed_min_radps",
               "must be below motor_speed_max_radps (" + Short(p.motor_speed_max_radps) + ")");
  }
  if (!(p.slack_epsilon_m < p.cable_length_m)) {
    YamlMap(root.Node("cable"), root.file(), root.KeyPath("cable"))
        .Fail("slack_epsilon_m", "must be below the cable's length_m (" + Short(p.cable_length_m) +
                                     "): slack is a distance shorter than the cable by it");
  }
  if (!(p.R_BC.transpose() * p.R_BC).isIdentity(1e-9) ||
      std::abs(p.R_BC.determinant() - 1) > 1e-9) {
    YamlMap(root.Node("payload_camera"), root.file(), root.KeyPath("payload_camera"))
        .Fail("R_BC", "not a rotation (R^T R != I or det != 1)");
  }
  root.RejectUnknownKeys();
  return p;
}

}  // namespace hpa
