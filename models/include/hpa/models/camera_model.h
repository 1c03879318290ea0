#pragma once
// The payload camera's geometry: body->camera transform and pinhole projection (no distortion).

#include <Eigen/Core>
#include <optional>

#include "hpa/models/params.h"
#include "hpa/models/state.h"

namespace hpa {

/// Payload centre in the camera frame C (OpenCV axes): p_C = (R R_BC)^T (x_L - x_Q - R t_BC),
/// DESIGN.md's corrected form of the paper's transform.
Eigen::Vector3d PayloadInCamera_C(const Params& params, const SystemState& state);

/// Pixel coordinates (u right, v down, origin top-left) of a camera-frame point, or nullopt if the
/// point is behind the camera.
std::optional<Eigen::Vector2d> ProjectToPixels(const Params& params, const Eigen::Vector3d& p_C);

/// True when the point is in front of the camera and projects inside the image.
bool InsideImage(const Params& params, const Eigen::Vector3d& p_C);

}  // namespace hpa
