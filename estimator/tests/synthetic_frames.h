#pragma once
// Test helper: exact synthetic payload-camera frames (a shaded red sphere on a grey floor),
// rendered by ray casting with 4x4 supersampling, for developing the detector without MuJoCo.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <random>

#include "hpa/estimator/payload_detector.h"
#include "hpa/models/params.h"

namespace hpa::testing_frames {

/// Draws the sphere of params.payload_radius_m centred at p_CL_C (camera frame) on a grey
/// background; adds Gaussian pixel noise of noise_std (grey levels) from `rng` if given.
inline cv::Mat RenderSphere(const Params& params, const Eigen::Vector3d& p_CL_C,
                            std::mt19937_64* rng = nullptr, double noise_std = 0.0) {
  const int width = params.camera_width_px, height = params.camera_height_px;
  const cv::Vec3d floor_bgr(120, 125, 128);
  cv::Mat image(height, width, CV_64FC3, cv::Scalar(floor_bgr[0], floor_bgr[1], floor_bgr[2]));
  const double f_px = params.CameraFocalPx();
  const double radius_m = params.payload_radius_m;
  const Eigen::Vector3d light_C = Eigen::Vector3d(0.3, -0.5, -1.0).normalized();  // toward light
  constexpr int kSub = 4;
  // only pixels near the exact outline's bounding box can see the sphere
  const Eigen::Matrix2Xd outline = SphereOutlinePx(params, p_CL_C, radius_m, 720);
  int u_min = width, u_max = -1, v_min = height, v_max = -1;
  if (outline.cols() > 0 && p_CL_C.z() > radius_m) {
    const Eigen::Vector2d lo = outline.rowwise().minCoeff(), hi = outline.rowwise().maxCoeff();
    u_min = std::max(0, static_cast<int>(std::floor(lo.x())) - 2);
    v_min = std::max(0, static_cast<int>(std::floor(lo.y())) - 2);
    u_max = std::min(width - 1, static_cast<int>(std::ceil(hi.x())) + 2);
    v_max = std::min(height - 1, static_cast<int>(std::ceil(hi.y())) + 2);
  }
  for (int v = v_min; v <= v_max; ++v) {
    for (int u = u_min; u <= u_max; ++u) {
      // quick reject: pixel ray far from the sphere direction
      const Eigen::Vector3d ray_centre((u + 0.5 - 0.5 * width) / f_px,
                                       (v + 0.5 - 0.5 * height) / f_px, 1.0);
      const Eigen::Vector3d rc = ray_centre.normalized();
      const double d_m = p_CL_C.norm();
      const double cos_alpha = std::sqrt(std::max(0.0, 1.0 - std::pow(radius_m / d_m, 2)));
      if (rc.dot(p_CL_C / d_m) < cos_alpha - 0.02) continue;
      cv::Vec3d sum(0, 0, 0);
      for (int i = 0; i < kSub; ++i) {
        for (int j = 0; j < kSub; ++j) {
          const Eigen::Vector3d ray =
              Eigen::Vector3d((u + (i + 0.5) / kSub - 0.5 * width) / f_px,
                              (v + (j + 0.5) / kSub - 0.5 * height) / f_px, 1.0)
                  .normalized();
          // ray-sphere intersection: t^2 - 2 t (ray.c) + |c|^2 - R^2 = 0
          const double b = ray.dot(p_CL_C);
          const double disc = b * b - (p_CL_C.squaredNorm() - radius_m * radius_m);
          if (disc < 0 || p_CL_C.z() <= 0) {
            sum += floor_bgr;
            continue;
          }
          const Eigen::Vector3d hit = (b - std::sqrt(disc)) * ray;
          const Eigen::Vector3d normal = (hit - p_CL_C) / radius_m;
          const double shade = 0.35 + 0.65 * std::max(0.0, normal.dot(light_C));
          sum += cv::Vec3d(10, 10, 230) * shade;
        }
      }
      image.at<cv::Vec3d>(v, u) = sum / (kSub * kSub);
    }
  }
  if (rng != nullptr && noise_std > 0) {
    // OpenCV's generator seeded from the caller's: deterministic and fast for 2.8 M samples
    cv::RNG cv_rng((*rng)());
    cv::Mat noise(image.size(), image.type());
    cv_rng.fill(noise, cv::RNG::NORMAL, 0.0, noise_std);
    image += noise;
  }
  cv::Mat out;
  image.convertTo(out, CV_8UC3);  // saturates to 0..255
  return out;
}

}  // namespace hpa::testing_frames
