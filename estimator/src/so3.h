#pragma once
// SO(3) helpers of the quadrotor filter (private to the estimator; tests may include this).

#include <Eigen/Core>

namespace hpa {

/// SO(3) exponential of a rotation vector (rad).
Eigen::Matrix3d ExpSo3(const Eigen::Vector3d& theta);
/// SO(3) logarithm: rotation vector (rad) of R.
Eigen::Vector3d LogSo3(const Eigen::Matrix3d& R);
/// Skew-symmetric matrix of v: Skew(v) w = v x w.
Eigen::Matrix3d Skew(const Eigen::Vector3d& v);

}  // namespace hpa
