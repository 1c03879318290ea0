#pragma once
// The MJCF of a cooperative team: N quadrotors, each on its own length-limited tendon cable, and
// one payload, built from the single-vehicle scene's vehicle and cable (docs/cooperative.md).

#include <string>

#include "hpa/models/cooperative_model.h"

namespace hpa::sim {

/// MJCF text for the team. Each vehicle i is body "quadrotor_<i>" (free joint
/// "quadrotor_<i>_joint", actuators "rotor_<i>_<k>" whose ctrl is rotor k's thrust in N) with
/// the mass, inertia, box, rotor sites and yaw gears of its params, on tendon "cable_<i>"
/// (range 0..its cable length) to site "attach_<i>" on body "payload" (free joint
/// "payload_joint") at its attachment point. The timestep, gravity, the tendon's solreflimit,
/// solimplimit and width, and the bodies' collision classes are those of single_scene_path
/// (models/scene.xml), read through MuJoCo; throws std::runtime_error if it cannot be loaded.
std::string CooperativeSceneXml(const CooperativeTeam& team, const std::string& single_scene_path);

/// The radius (m) of a rotor disc in the single-vehicle scene (its geom "rotor0_disc"), the
/// rotor's reach beyond its axis; throws std::runtime_error if the scene cannot be loaded or has
/// no such geom.
double SingleSceneRotorRadius_m(const std::string& single_scene_path);

}  // namespace hpa::sim
