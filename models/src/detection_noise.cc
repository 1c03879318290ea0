#include "hpa/models/detection_noise.h"

#include <algorithm>
#include <cmath>

#include "hpa/models/camera_model.h"

namespace hpa {

CameraNoiseModel MeasuredDetectorNoise() { return CameraNoiseModel{}; }

Eigen::Matrix3d DetectionCovariance_C(const Params& params, const CameraNoiseModel& noise,
                                      const Eigen::Vector3d& p_CL_C) {
  const double distance_m = std::max(p_CL_C.norm(), params.payload_radius_m);
  const Eigen::Vector3d d = p_CL_C / distance_m;
  const double f_px = params.CameraFocalPx();
  // a pixel subtends cos(theta)/f rad across and cos^2(theta)/f rad along the radial line at
  // theta off the optical axis; D = R / sin(alpha) gives dD = -D^2/R dalpha (alpha small)
  const double cos_theta = std::max(d.z(), 1e-3);
  const double lateral_var = std::pow(distance_m * cos_theta * noise.centre_std_px / f_px, 2);
  const double range_scale =
      distance_m * distance_m * cos_theta * cos_theta / (f_px * params.payload_radius_m);
  const double range_var = std::pow(range_scale, 2) * (std::pow(noise.semi_major_std_px, 2) +
                                                       std::pow(noise.semi_major_bias_px, 2));
  return lateral_var * (Eigen::Matrix3d::Identity() - d * d.transpose()) +
         range_var * d * d.transpose();
}

}  // namespace hpa
