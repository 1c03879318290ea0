#pragma once
// Hybrid mode detector (paper section V-C): slack when the low-pass-filtered cable length from
// the payload detections drops below l - epsilon, taut otherwise.

#include "hpa/models/params.h"
#include "hpa/models/state.h"

namespace hpa {

/// Tuning of the mode detector.
struct ModeDetectorConfig {
  // first-order low pass on the measured cable length; 30 ms passes 2/3 of a step per 30 Hz
  // frame, so a 1.5 m/s slack event is flagged within two frames while 2 mm detector noise is
  // 20x below the 50 mm threshold margin
  double filter_time_constant_s = 0.03;
};

/// Runs at the camera rate on the measured cable length |x_L - x_Q| = |p_BL_B|.
class ModeDetector {
 public:
  /// Starts in `initial` mode with the filter at initial_length_m.
  ModeDetector(const Params& params, const ModeDetectorConfig& config, CableMode initial,
               double initial_length_m);

  /// Feeds one measured cable length (m) captured at time_s; returns the new mode. Non-finite or
  /// out-of-order samples leave the mode unchanged.
  CableMode Update(double time_s, double cable_length_m);

  CableMode mode() const { return mode_; }
  double filtered_length_m() const { return filtered_length_m_; }
  /// Slack threshold l - epsilon (m).
  double threshold_m() const { return threshold_m_; }

 private:
  ModeDetectorConfig config_;
  double threshold_m_;
  CableMode mode_;
  double filtered_length_m_;
  double last_time_s_ = -1e300;
  bool started_ = false;
};

}  // namespace hpa
