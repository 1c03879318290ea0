// TeamWorld's checks after every step: MuJoCo's warnings (a run error) and the crash conditions
// (latched, the first one met).

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "team_world_impl.h"
#include "world_detail.h"

namespace hpa::sim {

// a MuJoCo warning is a run error, as in the single-vehicle World
void TeamWorld::Impl::CheckWarnings() {
  for (int k = 0; k < mjNWARNING; ++k) {
    const int count = d->warning[k].number;
    if (count == warning_count[k]) continue;
    warning_count[k] = count;
    const std::string text = TakeWarnings();
    if (k == mjWARN_BADQPOS || k == mjWARN_BADQVEL || k == mjWARN_BADQACC) {
      throw std::runtime_error("the team's physics diverged at t = " + std::to_string(time_s()) +
                               " s (MuJoCo: " + text +
                               "): the parameters cannot be simulated; a run error, not a crash");
    }
    throw std::runtime_error("MuJoCo warning at t = " + std::to_string(time_s()) + " s: " + text);
  }
}

void TeamWorld::Impl::LatchCrash(const std::string& reason) {
  if (crash.crashed) return;
  crash.crashed = true;
  crash.time_s = time_s();
  crash.reason = reason;
}

// vehicle whose box geom g is (-1: none)
int TeamWorld::Impl::VehicleOfGeom(int g) const {
  for (int i = 0; i < n; ++i) {
    if (box_geom[i] == g) return i;
  }
  return -1;
}

// the crash conditions, the first one met latched
void TeamWorld::Impl::CheckCrash() {
  if (crash.crashed) return;
  for (int body = -1; body < n; ++body) {
    if (!Block(Body(body)).allFinite()) return LatchCrash(TeamBodyName(body) + " non-finite state");
  }

  // a vehicle's box touching anything (the payload on the ground is not a crash)
  for (int c = 0; c < d->ncon; ++c) {
    const mjContact& con = d->contact[c];
    const int a = VehicleOfGeom(con.geom1), b = VehicleOfGeom(con.geom2);
    if (a < 0 && b < 0) continue;
    if (a >= 0 && b >= 0) {
      return LatchCrash("vehicle " + std::to_string(std::min(a, b)) + " and vehicle " +
                        std::to_string(std::max(a, b)) + " collide");
    }
    const int vehicle = a >= 0 ? a : b;
    const int other = a >= 0 ? con.geom2 : con.geom1;
    std::string what;
    if (other == ground_geom) {
      what = "ground";
    } else if (other == payload_geom) {
      what = "payload";
    } else {
      const char* name = mj_id2name(m, mjOBJ_GEOM, other);
      what = name ? name : "a geom";
    }
    return LatchCrash(TeamBodyName(vehicle) + " contact with " + what);
  }

  CheckCableStrikes();
  if (crash.crashed) return;

  // a vehicle's tilt past 90 deg: its body z below the horizon
  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix<double, 13, 1> x = Block(vehicles[i]);
    const Eigen::Quaterniond q_WB(x(6), x(7), x(8), x(9));
    if (q_WB.normalized().toRotationMatrix()(2, 2) < 0.0) {
      return LatchCrash(TeamBodyName(i) + " tilt > 90 deg");
    }
  }

  // any body outside the arena (kArenaHalfWidth_m, kArenaHeight_m)
  for (int body = -1; body < n; ++body) {
    const Eigen::Vector3d p = Block(Body(body)).head<3>();
    if (std::abs(p.x()) > kArenaHalfWidth_m || std::abs(p.y()) > kArenaHalfWidth_m || p.z() < 0.0 ||
        p.z() > kArenaHeight_m) {
      return LatchCrash(TeamBodyName(body) + " left the 20x20x10 m arena");
    }
  }
}

// a cable through another vehicle's rotors: MuJoCo's tendons have no contact geometry, so each
// cable (a straight segment while it is taut, the only time it can cut) is checked against every
// other vehicle's rotor disc, a flat cylinder of the vehicle's reach in its body's x-y plane; a
// strike is a crash, as a cable caught in a propeller is
void TeamWorld::Impl::CheckCableStrikes() {
  for (int i = 0; i < n; ++i) {
    if (!Taut(i)) continue;
    const Eigen::Vector3d a_W = Block(vehicles[i]).head<3>();
    const Eigen::Vector3d b_W = AttachPoint_W(i);
    for (int j = 0; j < n; ++j) {
      if (j == i) continue;
      const Eigen::Matrix<double, 13, 1> x = Block(vehicles[j]);
      const Eigen::Quaterniond q_WB = Eigen::Quaterniond(x(6), x(7), x(8), x(9)).normalized();
      const double reach_m = params(j).arm_length_m + rotor_radius_m;
      const double half_height_m = params(j).body_half_size_m.z();
      // samples no farther apart than the disc's half thickness: a crossing is never missed
      const int samples = static_cast<int>(std::ceil((b_W - a_W).norm() / half_height_m));
      for (int k = 0; k <= samples; ++k) {
        const Eigen::Vector3d p_B =
            q_WB.conjugate() * (a_W + (b_W - a_W) * k / samples - x.head<3>());
        if (std::abs(p_B.z()) <= half_height_m && p_B.head<2>().norm() <= reach_m) {
          return LatchCrash("cable " + std::to_string(i) + " strikes " + TeamBodyName(j) +
                            "'s rotors");
        }
      }
    }
  }
}

}  // namespace hpa::sim
