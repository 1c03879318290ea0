// World: MuJoCo warnings and crash checks.

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "hpa/models/input_error.h"
#include "hpa/models/rotor_model.h"
#include "hpa/sim/world.h"
#include "world_detail.h"

namespace hpa::sim {

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
