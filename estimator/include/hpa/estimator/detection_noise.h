#pragma once
// The payload detector's noise in image terms and the measurement covariance it implies: the
// flight code's model of its own detector (also what the simulated analytic camera draws from).

#include <Eigen/Core>

#include "hpa/models/params.h"

namespace hpa {

/// Detector noise in image terms. The detector's 3D error comes from the ellipse centre (lateral
/// error ~ D sigma_c / f) and the major semi-axis (range error ~ D^2 sigma_a / (f R)).
///
/// Defaults MEASURED with estimator_render_test (RenderedDetectorTest.ErrorStatisticsByRegion):
/// PayloadDetector on 135 frames rendered off-screen by sim/ (1280x720, payload 0.25-0.45 m from
/// the camera, 9x5 image positions, level and tilted quadrotor): 31 out of view (all rejected), 64
/// detected (45 fully visible, 19 partly cut), 40 cut near the 60% visible-outline threshold.
/// Errors against the exact ellipse of the true position, over the 45 fully visible frames:
///   ellipse centre  -0.009 +- 0.075 px (per image axis)
///   major semi-axis -0.031 +- 0.073 px (implied by the range error)
/// 3D error per region, mean / std / max per axis x, y, z of C (mm):
///   centre      (n=18)  0.03 -0.03 0.03 / 0.19 0.09 0.64 / 0.37 0.20 1.08
///   off-centre  (n=16)  0.09  0.04 0.08 / 0.23 0.13 0.43 / 0.72 0.32 0.97
///   near edge   (n=11)  0.05  0.08 0.36 / 0.24 0.11 0.16 / 0.49 0.28 0.72
///   partly out  (n=19)  0.10 -0.10 0.25 / 0.40 0.23 0.44 / 1.11 0.60 1.18
/// The renderer is noise-free, so these are quantisation and anti-aliasing errors; exact
/// synthetic frames with 3-grey-level pixel noise (estimator_test) give up to 2.7 mm, so real
/// sensor noise would dominate. The flight code's measurement covariance adds a 2 mm floor
/// (EstimatorConfig::detection_noise_floor_m) for attitude and time-sync errors.
struct CameraNoiseModel {
  double centre_std_px = 0.075;        // ellipse centre noise per image axis (1 sigma)
  double semi_major_std_px = 0.073;    // major semi-axis noise (1 sigma)
  double semi_major_bias_px = -0.031;  // mean major semi-axis error of the detector
  double dropout_probability = 0.0;    // fully visible payload missed (never seen rendered)
};

/// The noise figures measured from the real detector (same numbers as CameraNoiseModel{}).
CameraNoiseModel MeasuredDetectorNoise();

/// Covariance (m^2, camera frame) of a detection at p_CL_C under `noise`: lateral and range
/// parts from the pixel noise above, plus the semi-axis bias squared on the range.
Eigen::Matrix3d DetectionCovariance_C(const Params& params, const CameraNoiseModel& noise,
                                      const Eigen::Vector3d& p_CL_C);

}  // namespace hpa
