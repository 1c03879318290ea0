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

}  // namespace hpa
