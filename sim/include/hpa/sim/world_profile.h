#pragma once
// A realism profile of the simulated world: the parts a real flight has and the ideal world
// leaves out (contact, actuation spread and battery sag, compute and transport latency, model
// mismatch between the flight code's parameters and the world's). Every part is off in a
// default-constructed profile (the `ideal` world); models/profiles/flight.yaml switches them on
// with the source of every number. The scenario runner and the world read it; flight code
// never does.

#include <string>

namespace hpa::sim {

/// Contact between payload and vehicle (body box and rotor disks). Payload against the ground
/// and the quadrotor against the ground collide in every profile.
struct ContactProfile {
  bool enabled = false;  // payload collides with the body and the rotor disks
};

/// Per-vehicle actuation imperfections: coefficients drawn once per seed, battery sag in time.
struct ActuationProfile {
  bool enabled = false;
  double thrust_coefficient_spread = 0.0;  // 1-sigma relative spread of each rotor's k_f
  double torque_coefficient_spread = 0.0;  // 1-sigma relative spread of each rotor's k_m
  double battery_voltage_drop_per_s = 0.0;  // relative pack voltage drop per second of flight
};

/// Delays between the flight code's loops, applied in simulated time.
struct LatencyProfile {
  double compute_s = 0.0;    // high-level controller: state in to command out
  double transport_s = 0.0;  // command from the controller to the rate loop
  double estimate_s = 0.0;   // age of the estimate the high-level controller is given
};

/// Model mismatch: the world's parameters differ from the flight code's by a draw per seed
/// within the stated 1-sigma tolerances (each term zero: no mismatch).
struct MismatchProfile {
  bool enabled = false;
  double payload_mass_sigma_kg = 0.0;         // payload mass
  double cable_length_sigma_m = 0.0;          // cable length
  double inertia_sigma_fraction = 0.0;        // relative, each diagonal entry
  double quad_mass_sigma_kg = 0.0;            // quadrotor mass
  double thrust_coefficient_sigma_fraction = 0.0;  // relative, all rotors together
  double camera_position_sigma_m = 0.0;       // camera origin in the body, each axis
  double camera_angle_sigma_rad = 0.0;        // camera orientation in the body, each axis
};

/// The whole profile: its name and its parts.
struct WorldProfile {
  std::string name = "ideal";  // ideal | flight (the file it came from)
  ContactProfile contact;
  ActuationProfile actuation;
  LatencyProfile latency;
  MismatchProfile mismatch;
};

}  // namespace hpa::sim
