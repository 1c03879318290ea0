#pragma once
// What an IMU measures of a free body in MuJoCo, shared by World and TeamWorld.

#include <mujoco/mujoco.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace hpa::sim {

/// Specific force R_WB^T (a_W - gravity_W) of the free body whose joint's first dof is `dof`
/// (m/s^2, body frame), from MuJoCo's qacc (the acceleration at the start of the last mj_step2)
/// in the attitude q_WB of that same time; gravity_W_mps2 is the gravity vector (world frame).
inline Eigen::Vector3d SpecificForce_B(const mjData* data, int dof, const Eigen::Quaterniond& q_WB,
                                       const Eigen::Vector3d& gravity_W_mps2) {
  const Eigen::Vector3d a_W(data->qacc[dof], data->qacc[dof + 1], data->qacc[dof + 2]);
  return q_WB.normalized().toRotationMatrix().transpose() * (a_W - gravity_W_mps2);
}

}  // namespace hpa::sim
