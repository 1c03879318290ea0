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
/// PayloadDetector on 135 frames rendered off-screen by sim/ through the flight profile's camera
/// image model (1280x720 single-sample render, EuRoC-calibrated barrel distortion, 0.69 px PSF,
/// shot and read noise at gain 4, 5 ms motion blur of a payload moving at 0.5 m/s, the cable
/// drawn), payload 0.25-0.45 m from the camera at 9x5 image positions, level and tilted
/// quadrotor: 82 fully visible frames detected, 20 partly cut detected, 12 fully visible frames
/// lost where the cable, close to the lens, covers the ball (payload on the cable's side of the
/// image). Errors against the exact ellipse of the true position, over the 82 fully visible:
///   ellipse centre  0.039 +- 0.421 px (per image axis)
///   major semi-axis 0.100 +- 0.122 px (implied by the range error)
/// The analytic camera draws no position-dependent loss: its dropout stays 0.
struct CameraNoiseModel {
  double centre_std_px = 0.421;       // ellipse centre noise per image axis (1 sigma)
  double semi_major_std_px = 0.122;   // major semi-axis noise (1 sigma)
  double semi_major_bias_px = 0.100;  // mean major semi-axis error of the detector
  double dropout_probability = 0.0;   // fully visible payload missed (never seen rendered)
};

/// The noise figures measured from the real detector (same numbers as CameraNoiseModel{}).
CameraNoiseModel MeasuredDetectorNoise();

/// Covariance (m^2, camera frame) of a detection at p_CL_C under `noise`: lateral and range
/// parts from the pixel noise above, plus the semi-axis bias squared on the range.
Eigen::Matrix3d DetectionCovariance_C(const Params& params, const CameraNoiseModel& noise,
                                      const Eigen::Vector3d& p_CL_C);

}  // namespace hpa
