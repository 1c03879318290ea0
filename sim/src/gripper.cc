// The gripper: grab, minimum-jerk motion, release, and its rod's collision switch.

#include "hpa/sim/gripper.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hpa/sim/faults.h"
#include "hpa/sim/world.h"

namespace hpa::sim {

Gripper::Gripper(const GripperBinding& binding) : b_(binding) {
  if (b_.model == nullptr || b_.data == nullptr || b_.payload_radius_m == nullptr ||
      b_.step == nullptr || b_.t0_s == nullptr || b_.mocap < 0 || b_.weld < 0 ||
      b_.payload_qpos < 0) {
    throw std::logic_error("sim::Gripper: a binding without its world's hand, model or clock");
  }
}

double Gripper::time_s() const { return *b_.t0_s + *b_.step * World::kPhysicsDt_s; }

void Gripper::Grab() {
  // put the mocap body on the payload's current pose, then switch the weld on
  const mjtNum* qpos = b_.data->qpos + b_.payload_qpos;
  for (int i = 0; i < 3; ++i) b_.data->mocap_pos[3 * b_.mocap + i] = qpos[i];
  for (int i = 0; i < 4; ++i) b_.data->mocap_quat[4 * b_.mocap + i] = qpos[3 + i];
  moving_ = false;
  b_.model->eq_active[b_.weld] = 1;
  used_ = true;
  UpdateContact();
}

void Gripper::Move(const Eigen::Vector3d& to_W_m, double duration_s) {
  if (!to_W_m.allFinite() || !std::isfinite(duration_s)) {
    throw std::invalid_argument("World::GripperMove: non-finite target or duration");
  }
  from_W_m_ = Eigen::Map<const Eigen::Vector3d>(b_.data->mocap_pos + 3 * b_.mocap);
  to_W_m_ = to_W_m;
  start_step_ = *b_.step;
  end_step_ = *b_.step + std::max<int64_t>(1, std::llround(duration_s / World::kPhysicsDt_s));
  moving_ = true;
  used_ = true;
  UpdateContact();
}

void Gripper::Release() {
  // a late gripper
  if (b_.faults != nullptr && !b_.faults->empty() && b_.faults->DefersRelease(time_s())) return;
  Open();
}

void Gripper::Open() {
  b_.model->eq_active[b_.weld] = 0;
  moving_ = false;
}

void Gripper::Reset() {
  Open();
  solid_ = false;
  used_ = false;
}

bool Gripper::active() const { return b_.model->eq_active[b_.weld] != 0; }

void Gripper::Update() {
  if (!moving_) return;
  const int64_t span = std::max<int64_t>(1, end_step_ - start_step_);
  const double s = std::clamp(static_cast<double>(*b_.step - start_step_) / span, 0.0, 1.0);
  // minimum-jerk profile: zero velocity and acceleration at both ends
  const double blend = s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
  const Eigen::Vector3d p = from_W_m_ + blend * (to_W_m_ - from_W_m_);
  for (int i = 0; i < 3; ++i) b_.data->mocap_pos[3 * b_.mocap + i] = p(i);
  if (s >= 1.0) moving_ = false;
}

void Gripper::UpdateContact() {
  if (b_.rod_geom < 0 || !b_.contact) return;
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
  b_.model->geom_contype[b_.rod_geom] = 0;
  b_.model->geom_conaffinity[b_.rod_geom] = solid_ ? (2 | 4) : 0;
}

double Gripper::PayloadDistance() const {
  // payload sphere against the rod's capsule (axis along its frame's z, half-length size[1])
  const int g = b_.rod_geom;
  const Eigen::Map<const Eigen::Vector3d> c(b_.data->geom_xpos + 3 * g);
  const Eigen::Vector3d axis(b_.data->geom_xmat[9 * g + 2], b_.data->geom_xmat[9 * g + 5],
                             b_.data->geom_xmat[9 * g + 8]);
  const double half_length_m = b_.model->geom_size[3 * g + 1];
  const double radius_m = b_.model->geom_size[3 * g + 0];
  const Eigen::Map<const Eigen::Vector3d> p(b_.data->qpos + b_.payload_qpos);
  const double s = std::clamp((p - c).dot(axis), -half_length_m, half_length_m);
  return (p - (c + s * axis)).norm() - radius_m - *b_.payload_radius_m;
}

}  // namespace hpa::sim
