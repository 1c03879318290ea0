// The model-mismatch and actuation-spread draws of a world's vehicles.

#include "mismatch_draw.h"

#include <Eigen/Geometry>
#include <algorithm>

#include "hpa/models/seed_streams.h"

namespace hpa::sim {

MismatchDraw DrawMismatch(const Params& params, const WorldProfile& profile, std::mt19937_64* rng) {
  MismatchDraw out;
  out.params = params;
  std::normal_distribution<double> normal(0.0, 1.0);  // one for both parts: its draws in order
  const MismatchProfile& m = profile.mismatch;
  if (m.enabled) {
    Params& p = out.params;
    // a draw that leaves a field's declared range is brought back to it
    const auto draw = [&](double Params::*member, double sigma) {
      p.*member =
          ClampToDecl(FindParamDecl(ParamsTables(), member), p.*member + sigma * normal(*rng));
    };
    draw(&Params::payload_mass_kg, m.payload_mass_sigma_kg);
    draw(&Params::cable_length_m, m.cable_length_sigma_m);
    draw(&Params::quad_mass_kg, m.quad_mass_sigma_kg);
    for (int i = 0; i < 3; ++i) {
      p.inertia_B_kgm2(i) *= std::max(0.2, 1.0 + m.inertia_sigma_fraction * normal(*rng));
    }
    p.k_f_N_per_radps2 *= std::max(0.2, 1.0 + m.thrust_coefficient_sigma_fraction * normal(*rng));
    for (int i = 0; i < 3; ++i) p.t_BC_B_m(i) += m.camera_position_sigma_m * normal(*rng);
    Eigen::Vector3d dtheta_B;
    for (int i = 0; i < 3; ++i) dtheta_B(i) = m.camera_angle_sigma_rad * normal(*rng);
    if (dtheta_B.norm() > 0.0) {
      p.R_BC =
          Eigen::AngleAxisd(dtheta_B.norm(), dtheta_B.normalized()).toRotationMatrix() * p.R_BC;
    }
  }
  const ActuationProfile& a = profile.actuation;
  if (a.enabled) {
    for (int i = 0; i < 4; ++i) {
      out.rotor_kf(i) = std::max(0.2, 1.0 + a.thrust_coefficient_spread * normal(*rng));
      out.rotor_km(i) = std::max(0.2, 1.0 + a.torque_coefficient_spread * normal(*rng));
    }
  }
  return out;
}

CooperativeTeam DrawTeamMismatch(const CooperativeTeam& team, const WorldProfile& profile,
                                 uint64_t seed, std::vector<Eigen::Vector4d>* rotor_kf,
                                 std::vector<Eigen::Vector4d>* rotor_km) {
  CooperativeTeam world = team;
  rotor_kf->clear();
  rotor_km->clear();
  for (size_t i = 0; i < team.vehicles.size(); ++i) {
    std::mt19937_64 rng(DeriveVehicleSeed(seed, SeedStream::kMismatch, static_cast<int>(i)));
    Params flight = team.vehicles[i].params;
    flight.cable_length_m = team.vehicles[i].cable_length_m;
    const MismatchDraw draw = DrawMismatch(flight, profile, &rng);
    world.vehicles[i].params = draw.params;
    world.vehicles[i].params.cable_length_m = team.vehicles[i].params.cable_length_m;
    world.vehicles[i].cable_length_m = draw.params.cable_length_m;
    if (i == 0) {
      const double drawn_kg = draw.params.payload_mass_kg - flight.payload_mass_kg;
      world.payload_mass_kg = std::max(1e-3, team.payload_mass_kg + drawn_kg);
    }
    rotor_kf->push_back(draw.rotor_kf);
    rotor_km->push_back(draw.rotor_km);
  }
  return world;
}

}  // namespace hpa::sim
