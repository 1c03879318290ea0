#pragma once
// Whether a slack payload is held up (by a hand or a gripper) or falling: the vertical
// acceleration of a quadratic fitted to its recent detected positions. A free payload
// accelerates at -g; a held one near 0. The controller's camera term uses the answer to predict
// where the payload will be (a held payload stays where the hand keeps it, a free one falls onto
// the cable's sphere). The same fit gives a held payload's motion: a hand is not in free fall, so
// the free-fall tracker's velocity lags a hand that speeds up or stops.

#include <Eigen/Core>
#include <array>
#include <limits>

#include "hpa/models/params.h"

namespace hpa {

/// Tuning of the support detector.
struct SupportDetectorConfig {
  // detections fitted: those captured within this window of the newest (six frames at 30 Hz),
  // at least this many. With the detector's few-millimetre noise the fitted acceleration's
  // standard deviation is about 1 m/s^2 on six frames, far from the threshold either way.
  double window_s = 0.2;
  int min_detections = 4;
  // supported while the fitted vertical acceleration is above -fall_fraction g (halfway between
  // a held payload's 0 and a free one's -g)
  double fall_fraction = 0.5;
  // the fit's motion is carried at most this far past the newest detection (three frames)
  double max_extrapolation_s = 0.1;
  // the fit gives no motion when its horizontal residuals' RMS is above this: the detector's
  // noise is a few millimetres and a hand's path is near quadratic over the window, so more
  // means a jump in the detections (a wrong detection, or the vehicle's estimate reset)
  double max_motion_residual_m = 0.01;
};

/// Classifies a slack payload as held up or falling from its detections (world positions), and
/// gives a held one's motion from the same fit.
class SupportDetector {
 public:
  SupportDetector(const Params& params, const SupportDetectorConfig& config);

  /// Forgets the detections (at a slack entry or a re-taut: the cable held the payload before).
  void Clear();
  /// Takes one detected payload position p_WL_W captured at time_s; non-finite or out-of-order
  /// samples are ignored.
  void Add(double time_s, const Eigen::Vector3d& p_WL_W);
  /// True when the last fit said the payload is held up.
  bool supported() const { return supported_; }
  /// The last fit's vertical acceleration (m/s^2; 0 before the first fit).
  double accel_z_mps2() const { return fit_a_WL_W_.z(); }
  /// The last fit's position and velocity at time_s (carried from the newest detection with the
  /// fitted acceleration, at most max_extrapolation_s); false, and nothing written, without a
  /// fit or when its residuals say the detections jumped (max_motion_residual_m).
  bool MotionAt(double time_s, Eigen::Vector3d* p_WL_W, Eigen::Vector3d* v_WL_W) const;
  /// Capture time of the oldest detection in the last fit (-infinity before the first fit).
  double fit_start_s() const { return fit_start_s_; }

 private:
  static constexpr int kCapacity = 16;  // more than the window holds at the camera's rate
  struct Sample {
    double time_s;
    Eigen::Vector3d p_WL_W;
  };
  SupportDetectorConfig config_;
  double gravity_mps2_;
  std::array<Sample, kCapacity> samples_{};  // ring, oldest first from head_
  int head_ = 0;
  int count_ = 0;
  bool supported_ = false;
  bool motion_valid_ = false;  // a last fit, its horizontal residuals within the bound
  // the last fit at the newest detection's time
  double fit_time_s_ = 0.0;
  double fit_start_s_ = -std::numeric_limits<double>::infinity();
  Eigen::Vector3d fit_p_WL_W_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d fit_v_WL_W_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d fit_a_WL_W_ = Eigen::Vector3d::Zero();
};

}  // namespace hpa
