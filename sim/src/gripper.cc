// The gripper: grab, minimum-jerk motion, release, and its rod's collision switch.

#include "hpa/sim/gripper.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hpa/sim/world.h"

namespace hpa::sim {

void Gripper::Grab() {
  // put the mocap body on the payload's current pose, then switch the weld on
  const mjtNum* qpos = w_.data_->qpos + w_.ids_.payload_jnt_qpos;
  for (int i = 0; i < 3; ++i) w_.data_->mocap_pos[3 * w_.ids_.gripper_mocap + i] = qpos[i];
  for (int i = 0; i < 4; ++i) w_.data_->mocap_quat[4 * w_.ids_.gripper_mocap + i] = qpos[3 + i];
  moving_ = false;
  w_.model_->eq_active[w_.ids_.gripper_weld] = 1;
  used_ = true;
  UpdateContact();
}

void Gripper::Move(const Eigen::Vector3d& to_W_m, double duration_s) {
  if (!to_W_m.allFinite() || !std::isfinite(duration_s)) {
    throw std::invalid_argument("World::GripperMove: non-finite target or duration");
  }
  from_W_m_ = Eigen::Map<const Eigen::Vector3d>(w_.data_->mocap_pos + 3 * w_.ids_.gripper_mocap);
  to_W_m_ = to_W_m;
  start_step_ = w_.step_;
  end_step_ = w_.step_ + std::max<int64_t>(1, std::llround(duration_s / World::kPhysicsDt_s));
  moving_ = true;
  used_ = true;
  UpdateContact();
}

void Gripper::Release() {
  if (!w_.faults_.empty() && w_.faults_.DefersRelease(w_.time_s())) return;  // a late gripper
  Open();
}

void Gripper::Open() {
  w_.model_->eq_active[w_.ids_.gripper_weld] = 0;
  moving_ = false;
}

void Gripper::Reset() {
  Open();
  solid_ = false;
  used_ = false;
}

bool Gripper::active() const { return w_.model_->eq_active[w_.ids_.gripper_weld] != 0; }

void Gripper::Update() {
  if (!moving_) return;
  const int64_t span = std::max<int64_t>(1, end_step_ - start_step_);
  const double s = std::clamp(static_cast<double>(w_.step_ - start_step_) / span, 0.0, 1.0);
  // minimum-jerk profile: zero velocity and acceleration at both ends
  const double blend = s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
  const Eigen::Vector3d p = from_W_m_ + blend * (to_W_m_ - from_W_m_);
  for (int i = 0; i < 3; ++i) w_.data_->mocap_pos[3 * w_.ids_.gripper_mocap + i] = p(i);
  if (s >= 1.0) moving_ = false;
}

void Gripper::UpdateContact() {
  if (w_.ids_.gripper_geom < 0 || !w_.config_.profile.contact.enabled) return;
  // The rod stands for the hand: while it holds the payload the weld alone acts (no contact
  // fights it); when it lets go the hand opens and withdraws, so the rod turns solid only once
  // the payload is clear of it. From then on it stops the payload (contype 4) and the
  // quadrotor's body (contype 2), which is a crash.
  // A gripper no event has used in this run (grab or move) is not there at all (no hand).
  if (active() || !used_) {
    solid_ = false;
  } else if (!solid_) {
    solid_ = PayloadDistance() > 0.0;
  }
  w_.model_->geom_contype[w_.ids_.gripper_geom] = 0;
  w_.model_->geom_conaffinity[w_.ids_.gripper_geom] = solid_ ? (2 | 4) : 0;
}

double Gripper::PayloadDistance() const {
  // payload sphere against the rod's capsule (axis along its frame's z, half-length size[1])
  const int g = w_.ids_.gripper_geom;
  const Eigen::Map<const Eigen::Vector3d> c(w_.data_->geom_xpos + 3 * g);
  const Eigen::Vector3d axis(w_.data_->geom_xmat[9 * g + 2], w_.data_->geom_xmat[9 * g + 5],
                             w_.data_->geom_xmat[9 * g + 8]);
  const double half_length_m = w_.model_->geom_size[3 * g + 1];
  const double radius_m = w_.model_->geom_size[3 * g + 0];
  const Eigen::Map<const Eigen::Vector3d> p(w_.data_->qpos + w_.ids_.payload_jnt_qpos);
  const double s = std::clamp((p - c).dot(axis), -half_length_m, half_length_m);
  return (p - (c + s * axis)).norm() - radius_m - w_.world_params_.payload_radius_m;
}

}  // namespace hpa::sim
