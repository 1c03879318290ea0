#pragma once
// How a seed's world differs from the numbers the flight code flies with (private to sim): the
// profile's model-mismatch draw of a vehicle's parameters and its actuation part's rotor-to-rotor
// spread, one definition for the single vehicle's World and every vehicle of a TeamWorld.

#include <Eigen/Core>
#include <cstdint>
#include <random>
#include <vector>

#include "hpa/models/cooperative_model.h"
#include "hpa/models/params.h"
#include "hpa/sim/world_profile.h"

namespace hpa::sim {

/// One vehicle's draw: the world's parameters and its rotors' factors.
struct MismatchDraw {
  Params params;  // the flight code's params with the mismatch part's draw (as given when off)
  Eigen::Vector4d rotor_kf = Eigen::Vector4d::Ones();  // each rotor's thrust factor  (4)
  Eigen::Vector4d rotor_km = Eigen::Vector4d::Ones();  // each rotor's torque factor  (4)
};

/// `params` drawn by the profile's mismatch part (payload mass, cable length, quadrotor mass,
/// inertia, thrust coefficient, camera pose; a draw leaving a field's declared range is brought
/// back to it), then each rotor's thrust and torque factor by its actuation part, from `rng` in
/// that order; a part that is off draws nothing.
MismatchDraw DrawMismatch(const Params& params, const WorldProfile& profile, std::mt19937_64* rng);

/// A team's world: each vehicle i drawn by DrawMismatch from its own stream
/// (DeriveVehicleSeed(seed, SeedStream::kMismatch, i)) with its cable's length as the params'
/// cable length, which it then takes back; the payload's mass moved by vehicle 0's payload-mass
/// draw. Each vehicle's rotor factors into *rotor_kf and *rotor_km (N each).
CooperativeTeam DrawTeamMismatch(const CooperativeTeam& team, const WorldProfile& profile,
                                 uint64_t seed, std::vector<Eigen::Vector4d>* rotor_kf,
                                 std::vector<Eigen::Vector4d>* rotor_km);

}  // namespace hpa::sim
