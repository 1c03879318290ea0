#include "so3.h"

#include <Eigen/Geometry>

namespace hpa {

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

Eigen::Matrix3d ExpSo3(const Eigen::Vector3d& theta) {
  const double angle_rad = theta.norm();
  if (angle_rad < 1e-9) return Eigen::Matrix3d::Identity() + Skew(theta);
  return Eigen::AngleAxisd(angle_rad, theta / angle_rad).toRotationMatrix();
}

Eigen::Vector3d LogSo3(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

}  // namespace hpa
