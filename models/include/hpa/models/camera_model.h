#pragma once
// The payload camera's geometry: body->camera transform, pinhole projection, and the lens's
// radial-tangential distortion (Params::camera_distortion) between ideal and real pixels.

#include <Eigen/Core>
#include <optional>

#include "hpa/models/params.h"
#include "hpa/models/state.h"

namespace hpa {

/// Payload centre in the camera frame C (OpenCV axes): p_C = (R R_BC)^T (x_L - x_Q - R t_BC),
/// docs/design.md's corrected form of the paper's transform.
Eigen::Vector3d PayloadInCamera_C(const Params& params, const SystemState& state);

/// Pixel coordinates (u right, v down, origin top-left) of a camera-frame point, or nullopt if the
/// point is behind the camera.
std::optional<Eigen::Vector2d> ProjectToPixels(const Params& params, const Eigen::Vector3d& p_C);

/// True when the point is in front of the camera and projects inside the image.
bool InsideImage(const Params& params, const Eigen::Vector3d& p_C);

/// Distorted normalised coordinates of the ideal (pinhole) normalised coordinates x_n:
/// x_d = x_n (1 + k1 r^2 + k2 r^4) + tangential(p1, p2), r = |x_n| (OpenCV's model).
Eigen::Vector2d DistortNormalised(const Eigen::Vector4d& k1_k2_p1_p2, const Eigen::Vector2d& x_n);

/// Ideal normalised coordinates whose distorted image is x_d (Newton's method from `guess`, or
/// from x_d when null; exact to < 1e-12 inside the lens's monotonic range).
Eigen::Vector2d UndistortNormalised(const Eigen::Vector4d& k1_k2_p1_p2, const Eigen::Vector2d& x_d,
                                    const Eigen::Vector2d* guess = nullptr);

/// Ideal (pinhole) pixel of a real, distorted pixel (continuous coordinates, origin top-left).
Eigen::Vector2d UndistortPixel(const Params& params, const Eigen::Vector2d& distorted_px);

/// Real (distorted) pixel of an ideal pinhole pixel (continuous coordinates, origin top-left).
Eigen::Vector2d DistortPixel(const Params& params, const Eigen::Vector2d& ideal_px);

/// Fraction of an outline (ideal pinhole pixels, continuous coordinates, origin at the top-left
/// image corner) that the lens (Params::camera_distortion) puts inside the real image with a
/// 1 px margin.
double VisibleOutlineFraction(const Params& params, const Eigen::Matrix2Xd& outline_px);

/// Exact image outline of a sphere of radius_m centred at p_CL_C: n points on the tangent cone,
/// in continuous pixel coordinates (origin at the top-left corner, centre of the image at W/2,
/// H/2).
Eigen::Matrix2Xd SphereOutlinePx(const Params& params, const Eigen::Vector3d& p_CL_C,
                                 double radius_m, int n);

/// Sphere centre in C from the two major-axis end points of its image ellipse (pixels, continuous
/// coordinates): rays r1, r2; direction normalised(r1 + r2); distance R / sin(acos(r1.r2) / 2).
Eigen::Vector3d SphereCentreFromMajorAxis(const Params& params, const Eigen::Vector2d& end1_px,
                                          const Eigen::Vector2d& end2_px, double radius_m);

}  // namespace hpa
