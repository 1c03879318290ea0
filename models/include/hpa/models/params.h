#pragma once
// Physical parameters of the quadrotor-cable-payload system, loaded from models/params.yaml.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "hpa/models/param_table.h"

namespace hpa {

/// Every physical number of the system (docs/design.md section 2); SI units, z up.
struct Params {
  double gravity_mps2 = 9.81;

  double quad_mass_kg = 0.72;
  Eigen::Vector3d inertia_B_kgm2{0.0025, 0.0025, 0.0043};  // diagonal of J  (3)
  double arm_length_m = 0.15;                              // centre to rotor axis, X frame
  Eigen::Vector3d body_half_size_m{0.1, 0.1, 0.03};        // collision box half sizes  (3)

  double k_f_N_per_radps2 = 1.5e-6;   // rotor thrust f_i = k_f w_i^2
  double k_m_Nm_per_radps2 = 2.4e-8;  // rotor drag torque tau_i = k_m w_i^2
  double motor_time_constant_s = 0.03;
  double motor_speed_min_radps = 100.0;
  double motor_speed_max_radps = 1830.0;

  double payload_mass_kg = 0.1;
  double payload_radius_m = 0.04;

  double cable_length_m = 0.5;
  double slack_epsilon_m = 0.05;

  int camera_width_px = 1280;
  int camera_height_px = 720;
  double camera_fovy_deg = 75.0;
  Eigen::Vector3d t_BC_B_m{0.03, 0.0, -0.05};  // camera origin in body  (3)
  // radial-tangential lens distortion (k1, k2, p1, p2) on normalised coordinates; zero: pinhole
  // unaligned storage: a 16-byte-aligned member would change Params' alignment for every struct
  // that embeds it
  Vector4dUnaligned camera_distortion = Vector4dUnaligned::Zero();  // (4)
  Eigen::Matrix3d R_BC = Eigen::Vector3d(1, -1, -1).asDiagonal();   // camera axes in body (3x3)

  int vio_width_px = 640;
  int vio_height_px = 480;

  /// Total hover thrust of quadrotor + hanging payload.
  double HoverThrustN() const { return (quad_mass_kg + payload_mass_kg) * gravity_mps2; }
  /// Rotor speed at which four rotors carry quadrotor + payload.
  double HoverMotorSpeedRadps() const;
  /// One rotor's thrust at its slowest speed, k_f w_min^2 (N).
  double RotorThrustMinN() const {
    return k_f_N_per_radps2 * motor_speed_min_radps * motor_speed_min_radps;
  }
  /// One rotor's thrust at its fastest speed, k_f w_max^2 (N).
  double RotorThrustMaxN() const {
    return k_f_N_per_radps2 * motor_speed_max_radps * motor_speed_max_radps;
  }
  /// Camera focal length in pixels (square pixels), from fovy and the image height.
  double CameraFocalPx() const;
};

/// Every field of Params, declared once: one table per params.yaml section (the first, with
/// section "", holds the top-level keys), each entry with its YAML key, unit, range, meaning and
/// protocol name. params.yaml's reader and writer, the lockstep protocol's configuration and
/// `hpa schema params` are driven by it.
const std::vector<ParamTable<Params>>& ParamsTables();

/// Loads and validates params.yaml; throws InputError naming the file and key on any problem
/// (missing file, unknown key, wrong type, non-positive mass...).
Params LoadParams(const std::string& path);

/// Path of the repository's models/params.yaml (compiled in).
std::string DefaultParamsPath();

}  // namespace hpa
