#include "hpa/sim/analytic_camera.h"

#include <algorithm>
#include <cmath>

#include "hpa/models/camera_model.h"

namespace hpa::sim {

AnalyticCamera::AnalyticCamera(const Params& params, const CameraNoiseModel& noise,
                               double min_visible_outline, double min_area_px2)
    : params_(params),
      noise_(noise),
      min_visible_outline_(min_visible_outline),
      min_area_px2_(min_area_px2) {}

PayloadDetection AnalyticCamera::Measure(const Eigen::Vector3d& p_CL_C, double time_s,
                                         std::mt19937_64& rng) const {
  PayloadDetection detection;
  detection.time_s = time_s;
  const double radius_m = params_.payload_radius_m;
  const double distance_m = p_CL_C.norm();
  if (!p_CL_C.allFinite() || distance_m <= radius_m || p_CL_C.z() <= radius_m) {
    detection.reason = "no payload in view";
    return detection;
  }
  // visibility: the same rule as the detector, on the exact outline
  const double visible =
      VisibleOutlineFraction(params_, SphereOutlinePx(params_, p_CL_C, radius_m, 72));
  if (visible <= 0.0) {
    detection.reason = "no payload in view";
    return detection;
  }

  // exact image ellipse: cone axis at theta from the optical axis, half-angle alpha
  const Eigen::Vector3d d = p_CL_C / distance_m;
  const double alpha_rad = std::asin(radius_m / distance_m);
  const double theta_rad = std::acos(std::clamp(d.z(), -1.0, 1.0));
  const double f_px = params_.CameraFocalPx();
  const double denom = std::pow(std::cos(theta_rad), 2) - std::pow(std::sin(alpha_rad), 2);
  if (denom <= 1e-6) {
    detection.reason = "no payload in view";
    return detection;
  }
  const double semi_major_px = f_px * std::sin(alpha_rad) * std::cos(alpha_rad) / denom;
  const double semi_minor_px = f_px * std::sin(alpha_rad) / std::sqrt(denom);
  // ellipse centre: midpoint of the major axis, on the radial line at angle theta
  const Eigen::Vector2d principal_px(0.5 * params_.camera_width_px, 0.5 * params_.camera_height_px);
  const Eigen::Vector2d radial = d.head<2>().norm() > 1e-12
                                     ? Eigen::Vector2d(d.head<2>().normalized())
                                     : Eigen::Vector2d(1.0, 0.0);
  const double mid_px =
      0.5 * f_px * (std::tan(theta_rad + alpha_rad) + std::tan(theta_rad - alpha_rad));
  const Eigen::Vector2d centre_px = principal_px + mid_px * radial;
  if (M_PI * semi_major_px * semi_minor_px < min_area_px2_) {
    detection.reason = "too small";
    return detection;
  }
  if (visible < min_visible_outline_) {
    detection.reason = "partly out of view";
    return detection;
  }
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  if (noise_.dropout_probability > 0 && uniform(rng) < noise_.dropout_probability) {
    detection.reason = "missed (analytic dropout)";
    return detection;
  }

  // detector noise on the image ellipse, then the detector's back-projection
  std::normal_distribution<double> n01(0.0, 1.0);
  const Eigen::Vector2d noisy_centre_px =
      centre_px + noise_.centre_std_px * Eigen::Vector2d(n01(rng), n01(rng));
  const double noisy_semi_major_px =
      semi_major_px + noise_.semi_major_bias_px + noise_.semi_major_std_px * n01(rng);
  const Eigen::Vector2d axis = (noisy_centre_px - principal_px).norm() > 2.0
                                   ? Eigen::Vector2d((noisy_centre_px - principal_px).normalized())
                                   : radial;
  detection.p_CL_C =
      SphereCentreFromMajorAxis(params_, noisy_centre_px + noisy_semi_major_px * axis,
                                noisy_centre_px - noisy_semi_major_px * axis, radius_m);
  detection.found = true;
  detection.centre_px = noisy_centre_px;
  detection.radius_px = semi_minor_px;
  return detection;
}

}  // namespace hpa::sim
