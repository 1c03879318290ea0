#pragma once
// The teams sim tests fly: params.yaml vehicles on one rigid payload.

#include <Eigen/Core>
#include <cmath>

#include "hpa/models/cooperative_model.h"
#include "hpa/models/params.h"

namespace hpa::sim {

/// A team of n params.yaml vehicles on a payload of the given mass and inertia, attachments
/// spread on a circle of radius_m (a bar for n = 2, a triangle for n = 3), cables of lengths
/// 0.5, 0.6, 0.7 m.
inline CooperativeTeam TestTeam(int n, double payload_mass_kg,
                                const Eigen::Vector3d& inertia_kgm2, double radius_m) {
  const Params p = LoadParams(DefaultParamsPath());
  CooperativeTeam team;
  team.payload_mass_kg = payload_mass_kg;
  team.payload_inertia_P_kgm2 = inertia_kgm2;
  team.gravity_mps2 = p.gravity_mps2;
  for (int i = 0; i < n; ++i) {
    CooperativeVehicle v;
    v.params = p;
    v.cable_length_m = 0.5 + 0.1 * i;
    const double a = 2 * M_PI * i / n;
    v.p_PA_P_m = radius_m * Eigen::Vector3d(std::cos(a), std::sin(a), 0);
    team.vehicles.push_back(v);
  }
  return team;
}

/// A 0.2 kg, 0.5 m bar under two vehicles.
inline CooperativeTeam TestBar() {
  return TestTeam(2, 0.2, Eigen::Vector3d(1e-4, 4.2e-3, 4.2e-3), 0.2);
}

/// A 0.3 kg triangle under three vehicles.
inline CooperativeTeam TestTriangle() {
  return TestTeam(3, 0.3, Eigen::Vector3d(3e-3, 3e-3, 6e-3), 0.2);
}

}  // namespace hpa::sim
