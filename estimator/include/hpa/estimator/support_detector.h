#pragma once
// Whether a slack payload is held up (by a hand or a gripper) or falling: the vertical
// acceleration of a quadratic fitted to its recent detected heights. A free payload accelerates
// at -g; a held one near 0. The controller's camera term uses the answer to predict where the
// payload will be (a held payload stays where the hand keeps it, a free one falls onto the
// cable's sphere).

#include <array>

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
};

/// Classifies a slack payload as held up or falling from its detections (world heights).
class SupportDetector {
 public:
  SupportDetector(const Params& params, const SupportDetectorConfig& config);

  /// Forgets the detections (at a slack entry or a re-taut: the cable held the payload before).
  void Clear();
  /// Takes one detected payload height z_W_m captured at time_s; non-finite or out-of-order
  /// samples are ignored.
  void Add(double time_s, double z_W_m);
  /// True when the last fit said the payload is held up.
  bool supported() const { return supported_; }
  /// The last fit's vertical acceleration (m/s^2; 0 before the first fit).
  double accel_z_mps2() const { return accel_z_mps2_; }

 private:
  static constexpr int kCapacity = 16;  // more than the window holds at the camera's rate
  struct Sample {
    double time_s;
    double z_W_m;
  };
  SupportDetectorConfig config_;
  double gravity_mps2_;
  std::array<Sample, kCapacity> samples_{};  // ring, oldest first from head_
  int head_ = 0;
  int count_ = 0;
  bool supported_ = false;
  double accel_z_mps2_ = 0.0;
};

}  // namespace hpa
