// World: payload-vehicle distances, contact episodes, MuJoCo warnings and crash checks.

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "hpa/models/input_error.h"
#include "hpa/models/rotor_model.h"
#include "hpa/sim/world.h"
#include "world_detail.h"

namespace hpa::sim {

namespace {

// Signed distance (m) from point p to an axis-aligned box of half sizes h at the origin
// (negative inside: minus the depth to the nearest face).
double BoxSignedDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& h) {
  const Eigen::Vector3d q = p.cwiseAbs() - h;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

// Signed distance (m) from point p to a solid cylinder of radius r and half height h along z at
// the origin (negative inside).
double CylinderSignedDistance(const Eigen::Vector3d& p, double r, double h) {
  const Eigen::Vector2d q(p.head<2>().norm() - r, std::abs(p.z()) - h);
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

}  // namespace

double World::PayloadQuadDistance() const {
  const Eigen::Vector3d p_WL_W(data_->xpos + 3 * ids_.payload_body);
  const double radius_m = model_->geom_size[3 * ids_.payload_geom];
  // the payload centre in a geom's frame: R_WG^T (p_WL - p_WG)
  auto in_geom = [&](int g) {
    const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R_WG(data_->geom_xmat +
                                                                              9 * g);
    return Eigen::Vector3d(R_WG.transpose() * (p_WL_W - Eigen::Vector3d(data_->geom_xpos + 3 * g)));
  };
  const int box = ids_.quad_box_geom;
  double d = BoxSignedDistance(in_geom(box), Eigen::Vector3d(model_->geom_size + 3 * box));
  for (int i = 0; i < 4; ++i) {
    const int g = ids_.rotor_disc_geom[i];
    d = std::min(d, CylinderSignedDistance(in_geom(g), model_->geom_size[3 * g],
                                           model_->geom_size[3 * g + 1]));
  }
  return d - radius_m;
}

void World::UpdateGripperContact() {
  if (ids_.gripper_geom < 0 || !config_.profile.contact.enabled) return;
  // The rod stands for the hand: while it holds the payload the weld alone acts (no contact
  // fights it); when it lets go the hand opens and withdraws, so the rod turns solid only once
  // the payload is clear of it. From then on it stops the payload (contype 4) and the
  // quadrotor's body (contype 2), which is a crash.
  // A gripper no event has used in this run (grab or move) is not there at all (no hand).
  if (gripper_active() || !gripper_used_) {
    gripper_solid_ = false;
  } else if (!gripper_solid_) {
    gripper_solid_ = PayloadGripperDistance() > 0.0;
  }
  model_->geom_contype[ids_.gripper_geom] = 0;
  model_->geom_conaffinity[ids_.gripper_geom] = gripper_solid_ ? (2 | 4) : 0;
}

double World::PayloadGripperDistance() const {
  // payload sphere against the rod's capsule (axis along its frame's z, half-length size[1])
  const int g = ids_.gripper_geom;
  const Eigen::Map<const Eigen::Vector3d> c(data_->geom_xpos + 3 * g);
  const Eigen::Vector3d axis(data_->geom_xmat[9 * g + 2], data_->geom_xmat[9 * g + 5],
                             data_->geom_xmat[9 * g + 8]);
  const double half_length_m = model_->geom_size[3 * g + 1];
  const double radius_m = model_->geom_size[3 * g + 0];
  const Eigen::Map<const Eigen::Vector3d> p(data_->qpos + ids_.payload_jnt_qpos);
  const double s = std::clamp((p - c).dot(axis), -half_length_m, half_length_m);
  return (p - (c + s * axis)).norm() - radius_m - world_params_.payload_radius_m;
}

void World::UpdateContacts() {
  bool now[5] = {false, false, false, false, false};  // the ContactCounts fields, in order
  bool rotor_strike = false;
  for (int i = 0; i < data_->ncon; ++i) {
    const mjContact& c = data_->contact[i];
    for (const auto& [a, b] : {std::pair{c.geom1, c.geom2}, std::pair{c.geom2, c.geom1}}) {
      if (a == ids_.payload_geom) {
        if (b == ids_.quad_box_geom) now[0] = true;
        for (int r = 0; r < 4; ++r) rotor_strike |= b == ids_.rotor_disc_geom[r];
        if (b == ids_.ground_geom) now[2] = true;
        if (b == ids_.gripper_geom) now[4] = true;
      }
      if (a == ids_.ground_geom && model_->geom_bodyid[b] == ids_.quad_body) now[3] = true;
    }
  }
  now[1] = rotor_strike;
  int* counts[5] = {&contact_counts_.payload_body, &contact_counts_.payload_rotor,
                    &contact_counts_.payload_ground, &contact_counts_.quad_ground,
                    &contact_counts_.payload_gripper};
  for (int k = 0; k < 5; ++k) {
    if (now[k] && !touching_[k]) ++*counts[k];
    touching_[k] = now[k];
  }
  payload_quad_min_distance_m_ = std::min(payload_quad_min_distance_m_, PayloadQuadDistance());
  if (rotor_strike) LatchCrash("rotor_strike");
}

CrashStatus World::Crash() const { return crash_; }

void World::LatchCrash(const std::string& reason) {
  if (crash_.crashed) return;
  crash_.crashed = true;
  crash_.time_s = time_s();
  crash_.reason = reason;
}

void World::CheckWarnings() {
  for (int i = 0; i < mjNWARNING; ++i) {
    const int n = data_->warning[i].number;
    if (n == warning_count_[i]) continue;
    warning_count_[i] = n;
    const std::string text = TakeWarnings();
    if (i == mjWARN_BADQPOS || i == mjWARN_BADQVEL || i == mjWARN_BADQACC) {
      // MuJoCo has reset mjData: its integration diverged. That is the simulation failing
      // (parameters it cannot integrate), not a flight result: a run error, not a crash
      throw std::runtime_error("the physics diverged at t = " + std::to_string(time_s()) +
                               " s (MuJoCo: " + text +
                               "): the parameters cannot be simulated; a run error, not a crash");
    }
    throw std::runtime_error("MuJoCo warning at t = " + std::to_string(time_s()) + " s: " + text);
  }
}

void World::CheckCrash() {
  if (crash_.crashed) return;
  const Truth t = GetTruth();
  const SystemState& s = t.state;
  if (!s.AllFinite()) return LatchCrash("non-finite state");

  // any contact of the quadrotor body (ground or an obstacle); the payload against the body is
  // contact, not a crash (against a rotor: UpdateContacts), unless the payload lies on the
  // ground: then the body has struck the ground through it
  bool payload_on_ground = false, body_on_payload = false;
  for (int i = 0; i < data_->ncon; ++i) {
    const mjContact& c = data_->contact[i];
    const int b1 = model_->geom_bodyid[c.geom1], b2 = model_->geom_bodyid[c.geom2];
    const bool has_payload = c.geom1 == ids_.payload_geom || c.geom2 == ids_.payload_geom;
    payload_on_ground |=
        has_payload && (c.geom1 == ids_.ground_geom || c.geom2 == ids_.ground_geom);
    if (b1 != ids_.quad_body && b2 != ids_.quad_body) continue;
    const int other = b1 == ids_.quad_body ? c.geom2 : c.geom1;
    if (other == ids_.payload_geom) {
      body_on_payload = true;
      continue;
    }
    const char* name = mj_id2name(model_, mjOBJ_GEOM, other);
    return LatchCrash(std::string("quadrotor contact with ") + (name ? name : "a geom"));
  }
  if (payload_on_ground && body_on_payload) {
    return LatchCrash("quadrotor contact with the payload lying on the ground");
  }

  // tilt past 90 deg: body z points below the horizon
  if (s.q_WB.normalized().toRotationMatrix()(2, 2) < 0.0) return LatchCrash("tilt > 90 deg");

  const Eigen::Vector3d& p = s.p_WQ_W;
  if (std::abs(p.x()) > kArenaHalfWidth_m || std::abs(p.y()) > kArenaHalfWidth_m || p.z() < 0.0 ||
      p.z() > kArenaHeight_m) {
    return LatchCrash("left the 20x20x10 m arena");  // kArenaHalfWidth_m, kArenaHeight_m
  }
}

}  // namespace hpa::sim
