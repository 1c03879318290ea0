#include "hpa/models/camera_model.h"

#include <algorithm>
#include <cmath>

namespace hpa {

Eigen::Vector3d PayloadInCamera_C(const Params& params, const SystemState& state) {
  const Eigen::Matrix3d R_WB = state.q_WB.toRotationMatrix();
  return (R_WB * params.R_BC).transpose() * (state.p_WL_W - state.p_WQ_W - R_WB * params.t_BC_B_m);
}

std::optional<Eigen::Vector2d> ProjectToPixels(const Params& params, const Eigen::Vector3d& p_C) {
  if (p_C.z() <= 1e-6) return std::nullopt;
  const double f = params.CameraFocalPx();
  return Eigen::Vector2d(0.5 * params.camera_width_px + f * p_C.x() / p_C.z(),
                         0.5 * params.camera_height_px + f * p_C.y() / p_C.z());
}

bool InsideImage(const Params& params, const Eigen::Vector3d& p_C) {
  const auto px = ProjectToPixels(params, p_C);
  return px && px->x() >= 0 && px->x() < params.camera_width_px && px->y() >= 0 &&
         px->y() < params.camera_height_px;
}

Eigen::Vector2d DistortNormalised(const Eigen::Vector4d& k, const Eigen::Vector2d& x_n) {
  const double x = x_n.x(), y = x_n.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + k[0] * r2 + k[1] * r2 * r2;
  return Eigen::Vector2d(x * radial + 2.0 * k[2] * x * y + k[3] * (r2 + 2.0 * x * x),
                         y * radial + k[2] * (r2 + 2.0 * y * y) + 2.0 * k[3] * x * y);
}

Eigen::Vector2d UndistortNormalised(const Eigen::Vector4d& k, const Eigen::Vector2d& x_d,
                                    const Eigen::Vector2d* guess) {
  if (k.isZero()) return x_d;
  // Newton on F(x) = Distort(x) - x_d with the model's analytic Jacobian: converges in a few
  // steps over the whole image (plain fixed-point iteration diverges at the corners of a wide
  // lens), fewer from a neighbour's solution
  Eigen::Vector2d x = guess != nullptr ? *guess : x_d;
  for (int i = 0; i < 30; ++i) {
    const Eigen::Vector2d f = DistortNormalised(k, x) - x_d;
    if (f.squaredNorm() < 1e-26) break;
    const double u = x.x(), v = x.y(), r2 = u * u + v * v;
    const double radial = 1.0 + k[0] * r2 + k[1] * r2 * r2;
    const double dradial = 2.0 * k[0] + 4.0 * k[1] * r2;  // d(radial)/du = u * dradial
    Eigen::Matrix2d J;
    J(0, 0) = radial + u * dradial * u + 2.0 * k[2] * v + 6.0 * k[3] * u;
    J(0, 1) = u * dradial * v + 2.0 * k[2] * u + 2.0 * k[3] * v;
    J(1, 0) = v * dradial * u + 2.0 * k[2] * u + 2.0 * k[3] * v;
    J(1, 1) = radial + v * dradial * v + 6.0 * k[2] * v + 2.0 * k[3] * u;
    x -= J.inverse() * f;
  }
  return x;
}

Eigen::Vector2d UndistortPixel(const Params& params, const Eigen::Vector2d& distorted_px) {
  if (params.camera_distortion.isZero()) return distorted_px;
  const double f_px = params.CameraFocalPx();
  const Eigen::Vector2d c_px(0.5 * params.camera_width_px, 0.5 * params.camera_height_px);
  return c_px + f_px * UndistortNormalised(params.camera_distortion, (distorted_px - c_px) / f_px);
}

Eigen::Vector2d DistortPixel(const Params& params, const Eigen::Vector2d& ideal_px) {
  if (params.camera_distortion.isZero()) return ideal_px;
  const double f_px = params.CameraFocalPx();
  const Eigen::Vector2d c_px(0.5 * params.camera_width_px, 0.5 * params.camera_height_px);
  return c_px + f_px * DistortNormalised(params.camera_distortion, (ideal_px - c_px) / f_px);
}

namespace {

// Unit ray in C through a pixel (continuous coordinates, principal point at the image centre).
Eigen::Vector3d PixelRay_C(const Params& params, const Eigen::Vector2d& px) {
  const double f_px = params.CameraFocalPx();
  return Eigen::Vector3d((px.x() - 0.5 * params.camera_width_px) / f_px,
                         (px.y() - 0.5 * params.camera_height_px) / f_px, 1.0)
      .normalized();
}

}  // namespace

double VisibleOutlineFraction(const Params& params, const Eigen::Matrix2Xd& outline_px) {
  if (outline_px.cols() == 0) return 0.0;
  int inside = 0;
  for (int i = 0; i < outline_px.cols(); ++i) {
    if (outline_px(0, i) < -1e8) continue;  // behind the camera
    // where the lens puts the ideal outline point in the real image
    const Eigen::Vector2d real_px = DistortPixel(params, outline_px.col(i));
    const double u = real_px.x(), v = real_px.y();
    if (u >= 1.0 && u <= params.camera_width_px - 1.0 && v >= 1.0 &&
        v <= params.camera_height_px - 1.0) {
      ++inside;
    }
  }
  return static_cast<double>(inside) / outline_px.cols();
}

Eigen::Matrix2Xd SphereOutlinePx(const Params& params, const Eigen::Vector3d& p_CL_C,
                                 double radius_m, int n) {
  const double distance_m = p_CL_C.norm();
  if (!(distance_m > radius_m) || n <= 0) return Eigen::Matrix2Xd(2, 0);
  const Eigen::Vector3d d = p_CL_C / distance_m;
  const double alpha_rad = std::asin(radius_m / distance_m);
  // orthonormal basis (e1, e2) perpendicular to the cone axis d
  const Eigen::Vector3d seed =
      std::abs(d.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d e1 = d.cross(seed).normalized();
  const Eigen::Vector3d e2 = d.cross(e1);
  const double f_px = params.CameraFocalPx();
  Eigen::Matrix2Xd outline(2, n);
  for (int i = 0; i < n; ++i) {
    const double phi = 2.0 * M_PI * i / n;
    const Eigen::Vector3d ray =
        std::cos(alpha_rad) * d + std::sin(alpha_rad) * (std::cos(phi) * e1 + std::sin(phi) * e2);
    if (ray.z() <= 1e-9) {
      // behind the camera: mark as far outside the image
      outline.col(i).setConstant(-1e9);
      continue;
    }
    outline(0, i) = 0.5 * params.camera_width_px + f_px * ray.x() / ray.z();
    outline(1, i) = 0.5 * params.camera_height_px + f_px * ray.y() / ray.z();
  }
  return outline;
}

Eigen::Vector3d SphereCentreFromMajorAxis(const Params& params, const Eigen::Vector2d& end1_px,
                                          const Eigen::Vector2d& end2_px, double radius_m) {
  const Eigen::Vector3d r1 = PixelRay_C(params, end1_px);
  const Eigen::Vector3d r2 = PixelRay_C(params, end2_px);
  const double alpha_rad = 0.5 * std::acos(std::clamp(r1.dot(r2), -1.0, 1.0));
  const double distance_m = radius_m / std::sin(alpha_rad);
  return distance_m * (r1 + r2).normalized();
}

}  // namespace hpa
