#include "hpa/sim/world_profile.h"

namespace hpa::sim {

// Ranges: physically sensible bounds that keep a typo from flying (a pack flat in 100 s at most,
// latencies below 0.1 s, drag coefficients of blunt bodies, ...); the values and their sources
// are in models/profiles/flight.yaml.

const ParamTable<ContactProfile>& ContactParams() {
  using C = ContactProfile;
  static const ParamTable<C> t{
      "contact",
      "payload against the vehicle's body box and rotor disks, and a free gripper",
      {{"enabled", "", 0, 0, "payload collides with the body, the rotor disks and a free gripper",
        &C::enabled}}};
  return t;
}

const ParamTable<ActuationProfile>& ActuationParams() {
  using C = ActuationProfile;
  static const ParamTable<C> t{
      "actuation",
      "per-vehicle actuation imperfections: coefficients drawn once per seed, battery sag",
      {{"enabled", "", 0, 0, "switches the part on", &C::enabled},
       {"thrust_coefficient_spread", "-", 0.0, 0.3, "1-sigma relative spread of each rotor's k_f",
        &C::thrust_coefficient_spread},
       {"torque_coefficient_spread", "-", 0.0, 0.3, "1-sigma relative spread of each rotor's k_m",
        &C::torque_coefficient_spread},
       {"battery_voltage_drop_per_s", "1/s", 0.0, 0.01,
        "relative pack voltage drop per second of flight", &C::battery_voltage_drop_per_s}}};
  return t;
}

const ParamTable<LatencyProfile>& LatencyParams() {
  using C = LatencyProfile;
  static const ParamTable<C> t{
      "latency",
      "delays between the flight code's loops, in simulated time",
      {{"compute_s", "s", 0.0, 0.1, "high-level controller: state in to command out",
        &C::compute_s},
       {"transport_s", "s", 0.0, 0.1, "command from the controller to the rate loop",
        &C::transport_s},
       {"estimate_s", "s", 0.0, 0.1, "age of the estimate the high-level controller is given",
        &C::estimate_s}}};
  return t;
}

const ParamTable<MismatchProfile>& MismatchParams() {
  using C = MismatchProfile;
  static const ParamTable<C> t{
      "mismatch",
      "the world's parameters drawn per seed around the flight code's (1-sigma tolerances)",
      {{"enabled", "", 0, 0, "switches the part on", &C::enabled},
       {"payload_mass_sigma_kg", "kg", 0.0, 0.05, "payload mass", &C::payload_mass_sigma_kg},
       {"cable_length_sigma_m", "m", 0.0, 0.1, "cable length", &C::cable_length_sigma_m},
       {"quad_mass_sigma_kg", "kg", 0.0, 0.2, "quadrotor mass", &C::quad_mass_sigma_kg},
       {"inertia_sigma_fraction", "-", 0.0, 0.3, "relative, each diagonal entry of the inertia",
        &C::inertia_sigma_fraction},
       {"thrust_coefficient_sigma_fraction", "-", 0.0, 0.2, "relative, all rotors together",
        &C::thrust_coefficient_sigma_fraction},
       {"camera_position_sigma_m", "m", 0.0, 0.05, "camera origin in the body, each axis",
        &C::camera_position_sigma_m},
       {"camera_angle_sigma_rad", "rad", 0.0, 0.2, "camera orientation in the body, each axis",
        &C::camera_angle_sigma_rad}}};
  return t;
}

const ParamTable<AeroProfile>& AeroParams() {
  using C = AeroProfile;
  static const ParamTable<C> t{
      "aero",
      "rotor, body and payload drag against the airspeed (velocity minus wind)",
      {{"enabled", "", 0, 0, "switches the part on", &C::enabled},
       {"air_density_kgpm3", "kg/m^3", 0.5, 1.5, "air density", &C::air_density_kgpm3},
       {"rotor_drag_x_Nspm", "N s/m", 0.0, 10.0, "rotor drag, body x: F_B = -diag(x, y, 0) v_air",
        &C::rotor_drag_x_Nspm},
       {"rotor_drag_y_Nspm", "N s/m", 0.0, 10.0, "rotor drag, body y", &C::rotor_drag_y_Nspm},
       {"body_drag_coefficient_xy", "-", 0.0, 3.0, "quadratic drag Cd of the body box, x and y",
        &C::body_drag_coefficient_xy},
       {"body_drag_coefficient_z", "-", 0.0, 3.0, "quadratic drag Cd of the body box, z",
        &C::body_drag_coefficient_z},
       {"payload_drag_coefficient", "-", 0.0, 3.0, "quadratic drag Cd of the payload sphere",
        &C::payload_drag_coefficient}}};
  return t;
}

const ParamTable<WindProfile>& WindParams() {
  using C = WindProfile;
  static const ParamTable<C> t{
      "wind",
      "steady wind plus a Dryden-type gust per axis (first-order Gauss-Markov)",
      {{"mean_x_mps", "m/s", -30.0, 30.0, "steady wind, world x", &C::mean_x_mps},
       {"mean_y_mps", "m/s", -30.0, 30.0, "steady wind, world y", &C::mean_y_mps},
       {"mean_z_mps", "m/s", -10.0, 10.0, "steady wind, world z", &C::mean_z_mps},
       {"gust_sigma_mps", "m/s", 0.0, 10.0, "stationary std of the horizontal gust, each axis",
        &C::gust_sigma_mps},
       {"gust_length_m", "m", 0.1, 1000.0, "horizontal turbulence length L: tau = L / airspeed",
        &C::gust_length_m},
       {"gust_vertical_sigma_ratio", "-", 0.0, 2.0, "vertical gust std / horizontal",
        &C::gust_vertical_sigma_ratio},
       {"gust_vertical_length_m", "m", 0.1, 1000.0, "vertical turbulence length",
        &C::gust_vertical_length_m},
       {"gust_min_speed_mps", "m/s", 0.1, 30.0, "floor on the airspeed in L / airspeed (hover)",
        &C::gust_min_speed_mps}}};
  return t;
}

const ParamTable<VioDriftProfile>& VioDriftParams() {
  using C = VioDriftProfile;
  static const ParamTable<C> t{
      "vio",
      "VIO drift with distance flown, dropouts and re-localisation jumps",
      {{"enabled", "", 0, 0, "switches the part on", &C::enabled},
       {"position_drift_horizontal_m_per_sqrt_m", "m/sqrt(m)", 0.0, 1.0,
        "x, y drift std: this * sqrt(distance)", &C::position_drift_horizontal_m_per_sqrt_m},
       {"position_drift_vertical_m_per_sqrt_m", "m/sqrt(m)", 0.0, 1.0,
        "z drift std: this * sqrt(distance)", &C::position_drift_vertical_m_per_sqrt_m},
       {"yaw_drift_rad_per_sqrt_m", "rad/sqrt(m)", 0.0, 0.5, "yaw drift std: this * sqrt(distance)",
        &C::yaw_drift_rad_per_sqrt_m},
       {"dropout_rate_per_s", "1/s", 0.0, 10.0, "Poisson rate of dropouts (while tracking)",
        &C::dropout_rate_per_s},
       {"dropout_duration_s", "s", 0.0, 10.0, "no sample is delivered for this long",
        &C::dropout_duration_s},
       {"relocalisation_keep_fraction", "-", 0.0, 1.0,
        "drift kept when tracking resumes (0: all reset)", &C::relocalisation_keep_fraction},
       {"relocalisation_jump_horizontal_m", "m", 0.0, 5.0,
        "1-sigma step of x, y when tracking resumes", &C::relocalisation_jump_horizontal_m},
       {"relocalisation_jump_vertical_m", "m", 0.0, 5.0, "1-sigma step of z when tracking resumes",
        &C::relocalisation_jump_vertical_m},
       {"relocalisation_jump_yaw_rad", "rad", 0.0, 1.0, "1-sigma step of yaw when tracking resumes",
        &C::relocalisation_jump_yaw_rad}}};
  return t;
}

const ParamTable<ImuProfile>& ImuParams() {
  using C = ImuProfile;
  static const ParamTable<C> t{
      "imu",
      "the vehicle's IMU noise (off: the default sensor noise)",
      {{"enabled", "", 0, 0, "switches the part on", &C::enabled},
       {"gyro_noise_density_radps_rthz", "rad/s/sqrt(Hz)", 0.0, 0.1, "gyro white-noise density",
        &C::gyro_noise_density_radps_rthz},
       {"accel_noise_density_mps2_rthz", "m/s^2/sqrt(Hz)", 0.0, 1.0,
        "accelerometer white-noise density", &C::accel_noise_density_mps2_rthz}}};
  return t;
}

const ParamTable<CameraImageProfile>& CameraImageParams() {
  using C = CameraImageProfile;
  static const ParamTable<C> t{
      "camera",
      "the payload camera's image formation after the pinhole render",
      {{"psf_sigma_px", "px", 0.0, 5.0, "Gaussian PSF (lens blur and the pixel's area), 1 sigma",
        &C::psf_sigma_px},
       {"exposure_s", "s", 0.0, 0.03, "exposure time: motion blur over it (0: none)",
        &C::exposure_s},
       {"motion_blur_subframes", "-", 0, 64,
        "0: fast approximation; N >= 2: average of N exact renders", &C::motion_blur_subframes},
       {"noise", "", 0, 0, "shot and read noise", &C::noise},
       {"full_well_e", "e-", 100.0, 1e6, "electrons at full scale (gain 1)", &C::full_well_e},
       {"read_noise_e", "e-", 0.0, 100.0, "temporal read noise, rms", &C::read_noise_e},
       {"analog_gain", "-", 1.0, 64.0, "full scale = full_well_e / analog_gain electrons",
        &C::analog_gain},
       {"draw_cable", "", 0, 0, "the cable is drawn in the payload camera's image",
        &C::draw_cable}}};
  return t;
}

}  // namespace hpa::sim
