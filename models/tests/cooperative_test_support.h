#pragma once
// The draws and the bound the cooperative model's tests share: random teams, taut states and
// rotor speeds from the test's one generator, the relative difference of two derivatives and
// its bound against an independent model (RotorTM's transcription, HybridModel).

#include <Eigen/Dense>
#include <random>
#include <vector>

#include "hpa/models/cooperative_model.h"
#include "models/tests/rotor_tm_transcription.h"

namespace hpa::cooperative_test {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using Eigen::VectorXd;
using I = CooperativeStateIndex;
using rotor_tm::QuatToRot;

// ---------------------------------------------------------------------------------------------
// Random teams and taut configurations.

// A vector with entries uniform in [-1, 1], drawn from rng (the test's one source of randomness).
inline Vector3d RandomVector(std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  return Vector3d(unit(*rng), unit(*rng), unit(*rng));
}

// A team of n vehicles of params' kind, each with its own cable length, mass and attachment.
inline CooperativeTeam RandomTeam(int n, std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  CooperativeTeam team;
  const Params p;
  team.payload_mass_kg = 0.3 + 0.2 * unit(*rng);
  team.payload_inertia_P_kgm2 = Vector3d(3e-3, 4e-3, 6e-3) + 1e-3 * RandomVector(rng);
  for (int i = 0; i < n; ++i) {
    CooperativeVehicle v;
    v.params = p;
    v.params.quad_mass_kg = p.quad_mass_kg * (1 + 0.2 * unit(*rng));
    v.params.inertia_B_kgm2 = p.inertia_B_kgm2 * (1 + 0.2 * unit(*rng));
    v.cable_length_m = 0.5 + 0.3 * unit(*rng);
    v.p_PA_P_m = 0.2 * Vector3d(unit(*rng), unit(*rng), 0.3 * unit(*rng));
    team.vehicles.push_back(v);
  }
  return team;
}

// A unit quaternion (w, x, y, z) turning at most max_angle_rad about a random axis.
inline Eigen::Vector4d RandomQuaternion(std::mt19937* rng, double max_angle_rad) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const Eigen::Quaterniond q(
      Eigen::AngleAxisd(max_angle_rad * unit(*rng), RandomVector(rng).normalized()));
  return Eigen::Vector4d(q.w(), q.x(), q.y(), q.z());
}

// A state with every cable exactly at its length and not stretching (d = l, v_r = 0): the
// payload moving and rotating, each vehicle above its attachment, moving across its cable.
inline VectorXd RandomTautState(const CooperativeTeam& team, std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const int n = static_cast<int>(team.vehicles.size());
  VectorXd x = VectorXd::Zero(I::Size(n));
  x.segment<3>(I::kPayloadPos) = Vector3d(unit(*rng), unit(*rng), 1 + 0.5 * unit(*rng));
  x.segment<3>(I::kPayloadVel) = RandomVector(rng);
  x.segment<4>(I::kPayloadQuat) = RandomQuaternion(rng, 0.5);
  x.segment<3>(I::kPayloadRate) = 2 * RandomVector(rng);
  const Matrix3d R_WP = QuatToRot(x.segment<4>(I::kPayloadQuat));
  const Vector3d w_P = x.segment<3>(I::kPayloadRate);
  for (int i = 0; i < n; ++i) {
    const CooperativeVehicle& v = team.vehicles[i];
    const Vector3d p_A = x.segment<3>(I::kPayloadPos) + R_WP * v.p_PA_P_m;
    const Vector3d v_A = x.segment<3>(I::kPayloadVel) + R_WP * w_P.cross(v.p_PA_P_m);
    const Vector3d xi = Vector3d(0.6 * unit(*rng), 0.6 * unit(*rng), -1).normalized();
    const int b = I::Vehicle(i);
    x.segment<3>(b + I::kVehiclePos) = p_A - v.cable_length_m * xi;
    const Vector3d v_across = RandomVector(rng).cross(xi);  // perpendicular to xi
    x.segment<3>(b + I::kVehicleVel) = v_A + v_across;
    x.segment<4>(b + I::kVehicleQuat) = RandomQuaternion(rng, 0.6);
    x.segment<3>(b + I::kVehicleRate) = 3 * RandomVector(rng);
  }
  return x;
}

// Rotor speeds of n vehicles (4 each), hover +-30 %.
inline VectorXd RandomRotorSpeeds(int n, std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const double hover = Params().HoverMotorSpeedRadps();
  VectorXd u(4 * n);
  for (int k = 0; k < 4 * n; ++k) u[k] = hover * (1 + 0.3 * unit(*rng));
  return u;
}

// |a - b| / |b|.
inline double RelativeDifference(const VectorXd& a, const VectorXd& b) {
  return (a - b).norm() / b.norm();
}

// The relative difference over the cross-check's 1000 configurations per case is printed on the
// "[measured]" lines and recorded in docs/cooperative.md: the rounding of the same formulas
// evaluated in a different order. The bound is about 20x the largest measured and far below any
// physical term (a dropped or sign-flipped coupling term fails it by 1e-2 or more).
constexpr double kRotorTmTolerance = 1e-13;

}  // namespace hpa::cooperative_test
