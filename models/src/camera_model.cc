#include "hpa/models/camera_model.h"

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

}  // namespace hpa
