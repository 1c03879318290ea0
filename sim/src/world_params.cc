// World: the world's own parameters written into the MuJoCo model (masses, cable, rotors,
// contact settings, payload camera) and the profile's model-mismatch draw.

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/models/rotor_model.h"
#include "hpa/models/seed_streams.h"
#include "hpa/sim/world.h"
#include "mismatch_draw.h"
#include "world_detail.h"

namespace hpa::sim {

void World::ApplyWorldParams() {
  const Params& p = world_params_;
  model_->opt.gravity[0] = 0;
  model_->opt.gravity[1] = 0;
  model_->opt.gravity[2] = -p.gravity_mps2;

  // quadrotor mass and inertia
  model_->body_mass[ids_.quad_body] = p.quad_mass_kg;
  for (int i = 0; i < 3; ++i) model_->body_inertia[3 * ids_.quad_body + i] = p.inertia_B_kgm2(i);

  // payload: a solid sphere of the params' mass and radius
  model_->body_mass[ids_.payload_body] = p.payload_mass_kg;
  for (int i = 0; i < 3; ++i) {
    model_->body_inertia[3 * ids_.payload_body + i] =
        0.4 * p.payload_mass_kg * p.payload_radius_m * p.payload_radius_m;
  }
  const int sphere = mj_name2id(model_, mjOBJ_GEOM, "payload_sphere");
  if (sphere >= 0) {
    model_->geom_size[3 * sphere] = p.payload_radius_m;
    model_->geom_rbound[sphere] = p.payload_radius_m;
  }
  const int box = mj_name2id(model_, mjOBJ_GEOM, "quadrotor_box");
  if (box >= 0) {
    for (int i = 0; i < 3; ++i) model_->geom_size[3 * box + i] = p.body_half_size_m(i);
    model_->geom_rbound[box] = p.body_half_size_m.norm();
  }

  // cable length = the tendon's upper limit
  model_->tendon_range[2 * ids_.cable_tendon + 0] = 0.0;
  model_->tendon_range[2 * ids_.cable_tendon + 1] = p.cable_length_m;

  // rotors: thrust range from the motor bounds, sites at the params' arm length, yaw reaction
  // torque k_m / k_f per newton (the scene file holds the defaults; a --params file may differ)
  for (int i = 0; i < 4; ++i) {
    const int a = ids_.rotor_actuator[i];
    const int site = model_->actuator_trnid[2 * a];
    const Eigen::Vector3d r_B = RotorPosition_B(p, i);
    for (int k = 0; k < 3; ++k) model_->site_pos[3 * site + k] = r_B(k);
    const double k_f = p.k_f_N_per_radps2 * vehicle_->rotor_thrust_factor()(i);
    const double k_m = p.k_m_Nm_per_radps2 * vehicle_->rotor_torque_factor()(i);
    model_->actuator_gear[6 * a + 5] = RotorSpin(i) * k_m / k_f;
    model_->actuator_ctrlrange[2 * a + 0] = k_f * p.motor_speed_min_radps * p.motor_speed_min_radps;
    model_->actuator_ctrlrange[2 * a + 1] = k_f * p.motor_speed_max_radps * p.motor_speed_max_radps;
  }

  ApplyContactSettings();

  ApplyCameraPose(p);

  // derived constants (subtree masses, invweight0 used by the constraint softness)
  mj_setConst(model_, data_);
}

// Contact between payload and vehicle: the payload (contype 4) meets the body box and the rotor
// disks when their conaffinity has bit 4; the disks never touch the ground (contype 0).
// Solver settings for these contacts at the 1 ms step (checked by sim/tests/contact_test.cc):
// the payload's contacts are as stiff as MuJoCo resolves at this step (time constant 2 steps,
// critically damped: a hard ball against a carbon frame, no rebound of a soft contact), and the
// vehicle's geoms start their contact kContactMargin_m before the surfaces meet, so a payload
// arriving at up to kContactMargin_m per step is stopped before it overlaps the vehicle (the
// body's contact with the ground, a crash, then also counts from kContactMargin_m).
void World::ApplyContactSettings() {
  if (config_.profile.contact.enabled) {
    constexpr double kMargin_m = kContactMargin_m;
    model_->geom_conaffinity[ids_.quad_box_geom] |= 4;
    model_->geom_margin[ids_.quad_box_geom] = kMargin_m;
    for (int i = 0; i < 4; ++i) {
      model_->geom_contype[ids_.rotor_disc_geom[i]] = 0;
      model_->geom_conaffinity[ids_.rotor_disc_geom[i]] = 4;
      model_->geom_margin[ids_.rotor_disc_geom[i]] = kMargin_m;
    }
    model_->geom_solref[mjNREF * ids_.payload_geom + 0] = 2 * kPhysicsDt_s;
    model_->geom_solref[mjNREF * ids_.payload_geom + 1] = 1.0;
    // its solref wins in every pair it is in (MuJoCo mixes a pair's solref by solmix)
    model_->geom_solmix[ids_.payload_geom] = 1e3;
  }
}

// The payload camera: field of view, image size, and pose in the body. MuJoCo's camera axes are
// (x right, y up, looking along -z): R_B,mjcam = R_BC * diag(1, -1, -1) with C OpenCV's.
void World::ApplyCameraPose(const Params& p) {
  const int cam = ids_.payload_camera;
  model_->cam_fovy[cam] = p.camera_fovy_deg;
  for (int k = 0; k < 3; ++k) model_->cam_pos[3 * cam + k] = p.t_BC_B_m(k);
  const Eigen::Matrix3d R_B_mjcam = p.R_BC * Eigen::Vector3d(1, -1, -1).asDiagonal();
  const Eigen::Quaterniond q_B_mjcam(R_B_mjcam);
  model_->cam_quat[4 * cam + 0] = q_B_mjcam.w();
  model_->cam_quat[4 * cam + 1] = q_B_mjcam.x();
  model_->cam_quat[4 * cam + 2] = q_B_mjcam.y();
  model_->cam_quat[4 * cam + 3] = q_B_mjcam.z();
  model_->vis.global.offwidth = p.camera_width_px;
  model_->vis.global.offheight = p.camera_height_px;
}

void World::DrawMismatch() {
  // a generator of its own, so the sensor noise stream is the same with and without mismatch
  std::mt19937_64 rng(DeriveSeed(config_.seed, SeedStream::kMismatch));
  const MismatchDraw draw = sim::DrawMismatch(world_params_, config_.profile, &rng);
  world_params_ = draw.params;
  rotor_kf_draw_ = draw.rotor_kf;
  rotor_km_draw_ = draw.rotor_km;
}

}  // namespace hpa::sim
