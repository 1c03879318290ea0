#pragma once
// A test pose shared by the rendering tests: the payload swung +x and +y on a taut 0.5 m cable
// under a quadrotor at 1 m, optionally rolled, pitched and yawed.

#include <Eigen/Geometry>
#include <cmath>

#include "hpa/models/state.h"

namespace hpa::sim::testing_poses {

/// The swung-payload state (zero velocities); `tilted` also rotates the quadrotor.
inline SystemState SwungPayload(bool tilted) {
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0, 0, 1);
  const Eigen::Vector3d offset(0.1, 0.05, 0);
  s.p_WL_W = s.p_WQ_W + offset + Eigen::Vector3d(0, 0, -std::sqrt(0.25 - offset.squaredNorm()));
  if (tilted) {
    s.q_WB = Eigen::AngleAxisd(0.6, Eigen::Vector3d::UnitZ()) *
             Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()) *
             Eigen::AngleAxisd(-0.15, Eigen::Vector3d::UnitX());
  }
  return s;
}

}  // namespace hpa::sim::testing_poses
