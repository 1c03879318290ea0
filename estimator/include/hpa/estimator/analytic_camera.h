#pragma once
// Analytic payload camera for fast sweeps: the PayloadDetection the detector would return,
// computed from the TRUE payload position by exact sphere projection plus the detector's noise.

#include <Eigen/Core>
#include <random>

#include "hpa/models/params.h"
#include "hpa/models/sensor_types.h"

namespace hpa {

/// Detector noise in image terms. The detector's 3D error comes from the ellipse centre (lateral
/// error ~ D sigma_c / f) and the major semi-axis (range error ~ D^2 sigma_a / (f R)).
/// Defaults: MEASURED on MuJoCo/OSMesa frames (estimator_render_test, see the report there)
/// and on exact synthetic frames (estimator_test); see MeasuredDetectorNoise().
struct CameraNoiseModel {
  double centre_std_px = 0.15;       // ellipse centre noise per image axis (1 sigma)
  double semi_major_std_px = 0.15;   // major semi-axis noise (1 sigma)
  double semi_major_bias_px = 0.0;   // mean major semi-axis error of the detector
  double dropout_probability = 0.0;  // fully visible payload missed (never seen in rendering)
};

/// The noise figures measured from the real detector (same numbers as CameraNoiseModel{}).
CameraNoiseModel MeasuredDetectorNoise();

/// Covariance (m^2, camera frame) of a detection at p_CL_C under `noise`: lateral and range
/// parts from the pixel noise above, plus the semi-axis bias squared on the range.
Eigen::Matrix3d DetectionCovariance_C(const Params& params, const CameraNoiseModel& noise,
                                      const Eigen::Vector3d& p_CL_C);

/// Sensor model: same acceptance rules as PayloadDetector (too small, partly out of view with
/// the same visible-outline threshold), Gaussian noise on the image ellipse, then the detector's
/// own back-projection (SphereCentreFromMajorAxis).
class AnalyticCamera {
 public:
  AnalyticCamera(const Params& params, const CameraNoiseModel& noise = MeasuredDetectorNoise(),
                 double min_visible_outline = 0.60, double min_area_px2 = 200.0);

  /// Detection of a payload whose centre is truly at p_CL_C (camera frame) at time_s; noise
  /// from the caller's generator (the scenario's single source of randomness).
  PayloadDetection Measure(const Eigen::Vector3d& p_CL_C, double time_s,
                           std::mt19937_64& rng) const;

 private:
  Params params_;
  CameraNoiseModel noise_;
  double min_visible_outline_;
  double min_area_px2_;
};

}  // namespace hpa
