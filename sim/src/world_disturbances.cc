// World: wind, gusts and drag, scripted forces and impulses, and the gripper.

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "hpa/models/input_error.h"
#include "hpa/models/rotor_model.h"
#include "hpa/sim/world.h"
#include "world_detail.h"

namespace hpa::sim {

void World::UpdateGripper() {
  if (!gripper_moving_) return;
  const int64_t span = std::max<int64_t>(1, gripper_end_step_ - gripper_start_step_);
  const double s = std::clamp(static_cast<double>(step_ - gripper_start_step_) / span, 0.0, 1.0);
  // minimum-jerk profile: zero velocity and acceleration at both ends
  const double blend = s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
  const Eigen::Vector3d p = gripper_from_W_m_ + blend * (gripper_to_W_m_ - gripper_from_W_m_);
  for (int i = 0; i < 3; ++i) data_->mocap_pos[3 * ids_.gripper_mocap + i] = p(i);
  if (s >= 1.0) gripper_moving_ = false;
}

Eigen::Vector3d World::Wind_W_mps() const { return wind_->Wind_W_mps(step_); }

void World::SetWindVelocity(const Eigen::Vector3d& velocity_W_mps, double duration_s) {
  if (!velocity_W_mps.allFinite() || !std::isfinite(duration_s)) {
    throw std::invalid_argument("World::SetWindVelocity: non-finite velocity or duration");
  }
  wind_->SetEvent(velocity_W_mps, step_, std::llround(duration_s / kPhysicsDt_s));
}

void World::ApplyAerodynamics() {
  if (!config_.profile.aero.enabled && !wind_->gusty()) return;  // no air
  const Truth truth = GetTruth();
  const SystemState& s = truth.state;
  if (wind_->gusty()) wind_->StepGust(s.v_WQ_W);
  const AeroProfile& aero = config_.profile.aero;
  if (!aero.enabled) return;
  const Eigen::Vector3d wind_W = Wind_W_mps();
  const Eigen::Matrix3d R_WB = s.q_WB.normalized().toRotationMatrix();
  const Eigen::Vector3d air_B = R_WB.transpose() * (s.v_WQ_W - wind_W);  // airspeed, body  (3)

  // rotor drag: linear in the airspeed in the rotor plane (Faessler et al., RA-L 2018)
  Eigen::Vector3d f_B(-aero.rotor_drag_x_Nspm * air_B.x(), -aero.rotor_drag_y_Nspm * air_B.y(), 0);
  // body drag: quadratic, -0.5 rho |v| diag(Cd_i A_i) v over the box's faces
  const Eigen::Vector3d& h = world_params_.body_half_size_m;
  const Eigen::Vector3d cd_area_B_m2(aero.body_drag_coefficient_xy * 4 * h.y() * h.z(),
                                     aero.body_drag_coefficient_xy * 4 * h.x() * h.z(),
                                     aero.body_drag_coefficient_z * 4 * h.x() * h.y());
  f_B -= 0.5 * aero.air_density_kgpm3 * air_B.norm() * cd_area_B_m2.cwiseProduct(air_B);
  aero_quad_W_N_ = R_WB * f_B;
  // payload drag: a sphere
  const Eigen::Vector3d air_L_W = s.v_WL_W - wind_W;
  const double r = world_params_.payload_radius_m;
  aero_payload_W_N_ = -0.5 * aero.air_density_kgpm3 * aero.payload_drag_coefficient * M_PI * r * r *
                      air_L_W.norm() * air_L_W;
  for (int i = 0; i < 3; ++i) {
    data_->xfrc_applied[6 * ids_.quad_body + i] += aero_quad_W_N_(i);
    data_->xfrc_applied[6 * ids_.payload_body + i] += aero_payload_W_N_(i);
  }
}

void World::ApplyDisturbances() {
  mju_zero(data_->xfrc_applied, 6 * model_->nbody);
  ApplyAerodynamics();
  for (const TimedForce& f : forces_) {
    if (step_ >= f.end_step) continue;
    const int body = f.body == Body::kQuadrotor ? ids_.quad_body : ids_.payload_body;
    for (int i = 0; i < 3; ++i) data_->xfrc_applied[6 * body + i] += f.force_W_N(i);
  }
  forces_.erase(std::remove_if(forces_.begin(), forces_.end(),
                               [this](const TimedForce& f) { return step_ + 1 >= f.end_step; }),
                forces_.end());
}

void World::ApplyImpulse(Body body, const Eigen::Vector3d& impulse_W_Ns, double duration_s) {
  if (!impulse_W_Ns.allFinite() || !std::isfinite(duration_s)) {
    throw std::invalid_argument("World::ApplyImpulse: non-finite impulse or duration");
  }
  const int64_t steps = std::max<int64_t>(1, std::llround(duration_s / kPhysicsDt_s));
  forces_.push_back({body, impulse_W_Ns / (steps * kPhysicsDt_s), step_ + steps});
}

void World::AddVelocity(Body body, const Eigen::Vector3d& dv_W_mps) {
  if (!dv_W_mps.allFinite()) throw std::invalid_argument("World::AddVelocity: non-finite dv");
  // a free joint's first three velocity coordinates are its linear velocity in the world frame
  const int dof = body == Body::kQuadrotor ? ids_.quad_jnt_dof : ids_.payload_jnt_dof;
  for (int i = 0; i < 3; ++i) data_->qvel[dof + i] += dv_W_mps(i);
}

void World::SetWind(const Eigen::Vector3d& force_W_N, double duration_s) {
  if (!force_W_N.allFinite() || !std::isfinite(duration_s)) {
    throw std::invalid_argument("World::SetWind: non-finite force or duration");
  }
  const int64_t steps = std::max<int64_t>(0, std::llround(duration_s / kPhysicsDt_s));
  forces_.push_back({Body::kQuadrotor, force_W_N, step_ + steps});
}

void World::GripperGrab() {
  // put the mocap body on the payload's current pose, then switch the weld on
  const mjtNum* qpos = data_->qpos + ids_.payload_jnt_qpos;
  for (int i = 0; i < 3; ++i) data_->mocap_pos[3 * ids_.gripper_mocap + i] = qpos[i];
  for (int i = 0; i < 4; ++i) data_->mocap_quat[4 * ids_.gripper_mocap + i] = qpos[3 + i];
  gripper_moving_ = false;
  model_->eq_active[ids_.gripper_weld] = 1;
  gripper_used_ = true;
  UpdateGripperContact();
}

void World::GripperMove(const Eigen::Vector3d& to_W_m, double duration_s) {
  if (!to_W_m.allFinite() || !std::isfinite(duration_s)) {
    throw std::invalid_argument("World::GripperMove: non-finite target or duration");
  }
  gripper_from_W_m_ = Eigen::Map<const Eigen::Vector3d>(data_->mocap_pos + 3 * ids_.gripper_mocap);
  gripper_to_W_m_ = to_W_m;
  gripper_start_step_ = step_;
  gripper_end_step_ = step_ + std::max<int64_t>(1, std::llround(duration_s / kPhysicsDt_s));
  gripper_moving_ = true;
  gripper_used_ = true;
  UpdateGripperContact();
}

void World::GripperRelease() {
  if (!faults_.empty() && faults_.DefersRelease(time_s())) return;  // a late gripper
  model_->eq_active[ids_.gripper_weld] = 0;
  gripper_moving_ = false;
}

bool World::gripper_active() const { return model_->eq_active[ids_.gripper_weld] != 0; }

}  // namespace hpa::sim
