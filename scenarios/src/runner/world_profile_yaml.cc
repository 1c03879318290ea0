#include "hpa/scenarios/world_profile_yaml.h"

#include <cmath>
#include <map>
#include <mutex>

#include "hpa/models/input_error.h"
#include "hpa/models/yaml_reader.h"

namespace hpa {

const std::vector<std::string>& WorldProfileNames() {
  static const std::vector<std::string> names{"ideal", "flight"};
  return names;
}

void ReadWorldProfileSections(const YamlMap& map, sim::WorldProfile* profile) {
  if (map.Has("contact")) {
    const YamlMap m = map.Map("contact");
    profile->contact.enabled = m.Bool("enabled", profile->contact.enabled);
    m.RejectUnknownKeys();
  }
  if (map.Has("actuation")) {
    const YamlMap m = map.Map("actuation");
    sim::ActuationProfile& a = profile->actuation;
    a.enabled = m.Bool("enabled", a.enabled);
    a.thrust_coefficient_spread =
        m.Number("thrust_coefficient_spread", 0.0, 0.3, a.thrust_coefficient_spread);
    a.torque_coefficient_spread =
        m.Number("torque_coefficient_spread", 0.0, 0.3, a.torque_coefficient_spread);
    // at most a pack flat in 100 s: the scenarios are tens of seconds
    a.battery_voltage_drop_per_s =
        m.Number("battery_voltage_drop_per_s", 0.0, 0.01, a.battery_voltage_drop_per_s);
    m.RejectUnknownKeys();
  }
  if (map.Has("latency")) {
    const YamlMap m = map.Map("latency");
    sim::LatencyProfile& l = profile->latency;
    l.compute_s = m.Number("compute_s", 0.0, 0.1, l.compute_s);
    l.transport_s = m.Number("transport_s", 0.0, 0.1, l.transport_s);
    l.estimate_s = m.Number("estimate_s", 0.0, 0.1, l.estimate_s);
    m.RejectUnknownKeys();
  }
  if (map.Has("mismatch")) {
    const YamlMap m = map.Map("mismatch");
    sim::MismatchProfile& x = profile->mismatch;
    x.enabled = m.Bool("enabled", x.enabled);
    x.payload_mass_sigma_kg = m.Number("payload_mass_sigma_kg", 0.0, 0.05, x.payload_mass_sigma_kg);
    x.cable_length_sigma_m = m.Number("cable_length_sigma_m", 0.0, 0.1, x.cable_length_sigma_m);
    x.quad_mass_sigma_kg = m.Number("quad_mass_sigma_kg", 0.0, 0.2, x.quad_mass_sigma_kg);
    x.inertia_sigma_fraction =
        m.Number("inertia_sigma_fraction", 0.0, 0.3, x.inertia_sigma_fraction);
    x.thrust_coefficient_sigma_fraction = m.Number("thrust_coefficient_sigma_fraction", 0.0, 0.2,
                                                   x.thrust_coefficient_sigma_fraction);
    x.camera_position_sigma_m =
        m.Number("camera_position_sigma_m", 0.0, 0.05, x.camera_position_sigma_m);
    x.camera_angle_sigma_rad =
        m.Number("camera_angle_sigma_rad", 0.0, 0.2, x.camera_angle_sigma_rad);
    m.RejectUnknownKeys();
  }
  if (map.Has("aero")) {
    const YamlMap m = map.Map("aero");
    sim::AeroProfile& a = profile->aero;
    a.enabled = m.Bool("enabled", a.enabled);
    a.air_density_kgpm3 = m.Number("air_density_kgpm3", 0.5, 1.5, a.air_density_kgpm3);
    a.rotor_drag_x_Nspm = m.Number("rotor_drag_x_Nspm", 0.0, 10.0, a.rotor_drag_x_Nspm);
    a.rotor_drag_y_Nspm = m.Number("rotor_drag_y_Nspm", 0.0, 10.0, a.rotor_drag_y_Nspm);
    a.body_drag_coefficient_xy =
        m.Number("body_drag_coefficient_xy", 0.0, 3.0, a.body_drag_coefficient_xy);
    a.body_drag_coefficient_z =
        m.Number("body_drag_coefficient_z", 0.0, 3.0, a.body_drag_coefficient_z);
    a.payload_drag_coefficient =
        m.Number("payload_drag_coefficient", 0.0, 3.0, a.payload_drag_coefficient);
    m.RejectUnknownKeys();
  }
  if (map.Has("wind")) {
    const YamlMap m = map.Map("wind");
    sim::WindProfile& w = profile->wind;
    w.mean_x_mps = m.Number("mean_x_mps", -30.0, 30.0, w.mean_x_mps);
    w.mean_y_mps = m.Number("mean_y_mps", -30.0, 30.0, w.mean_y_mps);
    w.mean_z_mps = m.Number("mean_z_mps", -10.0, 10.0, w.mean_z_mps);
    w.gust_sigma_mps = m.Number("gust_sigma_mps", 0.0, 10.0, w.gust_sigma_mps);
    w.gust_length_m = m.Number("gust_length_m", 0.1, 1000.0, w.gust_length_m);
    w.gust_vertical_sigma_ratio =
        m.Number("gust_vertical_sigma_ratio", 0.0, 2.0, w.gust_vertical_sigma_ratio);
    w.gust_vertical_length_m =
        m.Number("gust_vertical_length_m", 0.1, 1000.0, w.gust_vertical_length_m);
    w.gust_min_speed_mps = m.Number("gust_min_speed_mps", 0.1, 30.0, w.gust_min_speed_mps);
    m.RejectUnknownKeys();
  }
  if (map.Has("vio")) {
    const YamlMap m = map.Map("vio");
    sim::VioDriftProfile& v = profile->vio;
    v.enabled = m.Bool("enabled", v.enabled);
    v.position_drift_horizontal_m_per_sqrt_m =
        m.Number("position_drift_horizontal_m_per_sqrt_m", 0.0, 1.0,
                 v.position_drift_horizontal_m_per_sqrt_m);
    v.position_drift_vertical_m_per_sqrt_m = m.Number("position_drift_vertical_m_per_sqrt_m", 0.0,
                                                      1.0, v.position_drift_vertical_m_per_sqrt_m);
    v.yaw_drift_rad_per_sqrt_m =
        m.Number("yaw_drift_rad_per_sqrt_m", 0.0, 0.5, v.yaw_drift_rad_per_sqrt_m);
    v.dropout_rate_per_s = m.Number("dropout_rate_per_s", 0.0, 10.0, v.dropout_rate_per_s);
    v.dropout_duration_s = m.Number("dropout_duration_s", 0.0, 10.0, v.dropout_duration_s);
    v.relocalisation_keep_fraction =
        m.Number("relocalisation_keep_fraction", 0.0, 1.0, v.relocalisation_keep_fraction);
    v.relocalisation_jump_horizontal_m =
        m.Number("relocalisation_jump_horizontal_m", 0.0, 5.0, v.relocalisation_jump_horizontal_m);
    v.relocalisation_jump_vertical_m =
        m.Number("relocalisation_jump_vertical_m", 0.0, 5.0, v.relocalisation_jump_vertical_m);
    v.relocalisation_jump_yaw_rad =
        m.Number("relocalisation_jump_yaw_rad", 0.0, 1.0, v.relocalisation_jump_yaw_rad);
    m.RejectUnknownKeys();
  }
  if (map.Has("imu")) {
    const YamlMap m = map.Map("imu");
    sim::ImuProfile& i = profile->imu;
    i.enabled = m.Bool("enabled", i.enabled);
    i.gyro_noise_density_radps_rthz =
        m.Number("gyro_noise_density_radps_rthz", 0.0, 0.1, i.gyro_noise_density_radps_rthz);
    i.accel_noise_density_mps2_rthz =
        m.Number("accel_noise_density_mps2_rthz", 0.0, 1.0, i.accel_noise_density_mps2_rthz);
    m.RejectUnknownKeys();
  }
  if (map.Has("camera")) {
    const YamlMap m = map.Map("camera");
    sim::CameraImageProfile& c = profile->camera;
    c.psf_sigma_px = m.Number("psf_sigma_px", 0.0, 5.0, c.psf_sigma_px);
    c.exposure_s = m.Number("exposure_s", 0.0, 0.03, c.exposure_s);
    c.motion_blur_subframes =
        static_cast<int>(m.Integer("motion_blur_subframes", 0, 64, c.motion_blur_subframes));
    if (c.motion_blur_subframes == 1) {
      m.Fail("motion_blur_subframes", "0 (fast approximation) or at least 2 sub-frames");
    }
    c.noise = m.Bool("noise", c.noise);
    c.full_well_e = m.Number("full_well_e", 100.0, 1e6, c.full_well_e);
    c.read_noise_e = m.Number("read_noise_e", 0.0, 100.0, c.read_noise_e);
    c.analog_gain = m.Number("analog_gain", 1.0, 64.0, c.analog_gain);
    c.draw_cable = m.Bool("draw_cable", c.draw_cable);
    m.RejectUnknownKeys();
  }
  if (map.Has("rate_loop")) {
    const YamlMap m = map.Map("rate_loop");
    sim::RateLoopProfile& r = profile->rate_loop;
    r.px4 = m.Bool("px4", r.px4);
    // the gyro is sampled on the physics clock (1 kHz): a whole number of steps per sample
    r.rate_hz = m.Number("rate_hz", 50.0, 1000.0, r.rate_hz);
    const double steps = 1000.0 / r.rate_hz;
    if (std::abs(steps - std::round(steps)) > 1e-9) {
      m.Fail("rate_hz", "a rate that divides the 1000 Hz physics rate (1000, 500, 250, ...)");
    }
    // ranges: PX4's parameter declarations (@min/@max; no @max given: a generous bound)
    const auto read3 = [&m](const char* key, double min, double max, std::array<double, 3>* v) {
      if (!m.Has(key)) return;
      const Eigen::VectorXd x = m.Vector(key, 3, min, max);
      for (int k = 0; k < 3; ++k) (*v)[k] = x(k);
    };
    read3("p", 0.0, 0.6, &r.p);
    read3("i", 0.0, 5.0, &r.i);
    read3("d", 0.0, 0.05, &r.d);
    read3("k", 0.01, 5.0, &r.k);
    read3("integrator_limit", 0.0, 1.0, &r.integrator_limit);
    r.gyro_cutoff_hz = m.Number("gyro_cutoff_hz", 0.0, 1000.0, r.gyro_cutoff_hz);
    r.dgyro_cutoff_hz = m.Number("dgyro_cutoff_hz", 0.0, 1000.0, r.dgyro_cutoff_hz);
    r.yaw_torque_cutoff_hz = m.Number("yaw_torque_cutoff_hz", 0.0, 10.0, r.yaw_torque_cutoff_hz);
    m.RejectUnknownKeys();
  }
}

sim::WorldProfile LoadWorldProfile(const std::string& name) {
  static std::mutex mutex;
  static std::map<std::string, sim::WorldProfile> cache;
  std::lock_guard<std::mutex> lock(mutex);
  if (auto it = cache.find(name); it != cache.end()) return it->second;
  bool known = false;
  for (const std::string& n : WorldProfileNames()) known = known || n == name;
  if (!known) throw InputError("", "world.profile", "unknown profile '" + name + "'");
  const std::string file = std::string(HPA_SOURCE_DIR) + "/models/profiles/" + name + ".yaml";
  const YamlMap root = YamlMap::LoadFile(file);
  sim::WorldProfile profile;
  profile.name = name;
  ReadWorldProfileSections(root, &profile);
  root.RejectUnknownKeys();
  cache[name] = profile;
  return profile;
}

}  // namespace hpa
