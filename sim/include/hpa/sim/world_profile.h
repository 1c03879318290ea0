#pragma once
// A realism profile of the simulated world: the parts a real flight has and the ideal world
// leaves out (contact, actuation spread and battery sag, compute and transport latency, model
// mismatch between the flight code's parameters and the world's, the camera's motion blur and
// sensor noise, the rate loop's own gyro). Every part is off in a default-constructed
// profile (the `ideal` world; the camera's lens PSF stays on); models/profiles/flight.yaml switches
// them on with the source of every number. The scenario runner and the world read it; flight code
// never does.

#include <string>

#include "hpa/models/param_table.h"

namespace hpa::sim {

/// Contact between payload and vehicle (body box and rotor disks), and of both with the gripper
/// while it does not hold the payload. Payload against the ground and the quadrotor against the
/// ground collide in every profile.
struct ContactProfile {
  bool enabled = false;  // payload collides with the body, the rotor disks and a free gripper
};

/// Per-vehicle actuation imperfections: coefficients drawn once per seed, battery sag in time.
struct ActuationProfile {
  bool enabled = false;
  double thrust_coefficient_spread = 0.0;   // 1-sigma relative spread of each rotor's k_f
  double torque_coefficient_spread = 0.0;   // 1-sigma relative spread of each rotor's k_m
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
  double payload_mass_sigma_kg = 0.0;              // payload mass
  double cable_length_sigma_m = 0.0;               // cable length
  double inertia_sigma_fraction = 0.0;             // relative, each diagonal entry
  double quad_mass_sigma_kg = 0.0;                 // quadrotor mass
  double thrust_coefficient_sigma_fraction = 0.0;  // relative, all rotors together
  double camera_position_sigma_m = 0.0;            // camera origin in the body, each axis
  double camera_angle_sigma_rad = 0.0;             // camera orientation in the body, each axis
};

/// Air: rotor drag, body drag and payload drag against the airspeed (velocity minus wind).
struct AeroProfile {
  bool enabled = false;
  double air_density_kgpm3 = 1.225;
  // rotor drag F_B = -diag(x, y, 0) (airspeed in the body frame), N s/m
  double rotor_drag_x_Nspm = 0.0, rotor_drag_y_Nspm = 0.0;
  // quadratic drag Cd of the body box per body axis (faces from body_half_size_m)
  double body_drag_coefficient_xy = 0.0, body_drag_coefficient_z = 0.0;
  double payload_drag_coefficient = 0.0;  // quadratic drag Cd of the payload sphere
};

/// Wind at the vehicle: a steady part plus a Dryden-type gust per axis (first-order
/// Gauss-Markov with stationary std gust_sigma_mps and correlation length gust_length_m).
struct WindProfile {
  double mean_x_mps = 0.0, mean_y_mps = 0.0, mean_z_mps = 0.0;  // steady wind, world frame
  double gust_sigma_mps = 0.0;                // stationary std of the horizontal gust, each axis
  double gust_length_m = 23.05;               // horizontal turbulence length L: tau = L / airspeed
  double gust_vertical_sigma_ratio = 0.5094;  // vertical gust std / horizontal
  double gust_vertical_length_m = 3.048;      // vertical turbulence length
  double gust_min_speed_mps = 1.0;            // floor on the airspeed in L / airspeed (hover)
};

/// VIO that drifts as a real one: position and yaw random walks with distance travelled, white
/// velocity noise, dropouts and re-localisation jumps (VioModel).
struct VioDriftProfile {
  bool enabled = false;
  double position_drift_horizontal_m_per_sqrt_m = 0.0;  // x, y drift std: this * sqrt(distance)
  double position_drift_vertical_m_per_sqrt_m = 0.0;    // z drift std: this * sqrt(distance)
  double yaw_drift_rad_per_sqrt_m = 0.0;                // yaw drift std: this * sqrt(distance)
  double dropout_rate_per_s = 0.0;                      // Poisson rate of dropouts (while tracking)
  double dropout_duration_s = 0.0;                      // no sample is delivered for this long
  double relocalisation_keep_fraction = 1.0;      // drift kept when tracking resumes (0: all reset)
  double relocalisation_jump_horizontal_m = 0.0;  // 1-sigma step of x, y when tracking resumes
  double relocalisation_jump_vertical_m = 0.0;    // 1-sigma step of z when tracking resumes
  double relocalisation_jump_yaw_rad = 0.0;       // 1-sigma step of yaw when tracking resumes
};

/// IMU noise of the flight profile (the vehicle's own IMU part); unset keeps SensorNoiseConfig.
struct ImuProfile {
  bool enabled = false;
  double gyro_noise_density_radps_rthz = 0.0;
  double accel_noise_density_mps2_rthz = 0.0;
};

/// The payload camera's image formation after the pinhole render (CameraImageModel). The lens's
/// point-spread function is on in every profile: it stands in for the pixel area a single-sample
/// render does not integrate. Motion blur and sensor noise are parts of the flight profile.
struct CameraImageProfile {
  double psf_sigma_px = 0.69;     // Gaussian PSF (lens blur and the pixel's own area), 1 sigma
  double exposure_s = 0.0;        // exposure time: motion blur over it (0: none)
  int motion_blur_subframes = 0;  // 0: fast approximation; N >= 2: average of N exact renders
  bool noise = false;             // shot and read noise
  double full_well_e = 7079.0;    // electrons at full scale (gain 1)
  double read_noise_e = 2.9;      // temporal read noise, electrons rms
  double analog_gain = 1.0;       // full scale = full_well_e / analog_gain electrons
  bool draw_cable = true;         // the cable is drawn in the payload camera's image
};

/// The rate loop's own gyro, a sensor of the vehicle: sampled at rate_hz when the flight code
/// flies PX4's rate loop (which runs on each of its samples), absent otherwise. The loop's gains
/// are flight-code parameters (hpa::Px4RateParams), not part of the world.
struct RateGyroProfile {
  bool enabled = false;
  double rate_hz = 1000.0;  // sample rate; divides the 1 kHz physics rate
};

/// The whole profile: its name and its parts.
struct WorldProfile {
  std::string name = "ideal";  // ideal | flight (the file it came from)
  ContactProfile contact;
  ActuationProfile actuation;
  LatencyProfile latency;
  MismatchProfile mismatch;
  AeroProfile aero;
  WindProfile wind;
  VioDriftProfile vio;
  ImuProfile imu;
  CameraImageProfile camera;
  RateGyroProfile rate_gyro;
};

/// The declared parameters of each section (YAML key, unit, range, meaning): the profile
/// loader, `hpa schema world` and docs/world_profiles.md read them.
const ParamTable<ContactProfile>& ContactParams();
const ParamTable<ActuationProfile>& ActuationParams();
const ParamTable<LatencyProfile>& LatencyParams();
const ParamTable<MismatchProfile>& MismatchParams();
const ParamTable<AeroProfile>& AeroParams();
const ParamTable<WindProfile>& WindParams();
const ParamTable<VioDriftProfile>& VioDriftParams();
const ParamTable<ImuProfile>& ImuParams();
const ParamTable<CameraImageProfile>& CameraImageParams();

}  // namespace hpa::sim
