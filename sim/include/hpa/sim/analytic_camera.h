#pragma once
// Analytic payload camera for fast sweeps: a simulated sensor giving the PayloadDetection the
// detector would return, computed from the TRUE payload position by exact sphere projection
// plus the detector's measured noise. Fed truth, so it lives in sim/, never in flight code.

#include <Eigen/Core>
#include <random>

#include "hpa/models/detection_noise.h"
#include "hpa/models/params.h"
#include "hpa/models/sensor_types.h"

namespace hpa::sim {

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

}  // namespace hpa::sim
