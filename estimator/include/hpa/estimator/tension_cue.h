#pragma once
// A slack cue the vehicle has for free (beyond the paper): the cable tension that the IMU's
// specific force and the collective thrust imply. Taut, the cable pulls the quadrotor with
// T xi; m s_W = f R e3 + T xi (s: specific force), so T = xi . (m s_W - f R e3). A payload
// taken by a hand or a gripper unloads the cable at once, long before it has risen the
// epsilon = 5 cm the geometric detector needs.

#include <Eigen/Core>

#include "hpa/models/params.h"

namespace hpa {

/// Tuning of the tension cue.
struct TensionCueConfig {
  bool enabled = true;  // false: the paper's geometric detector alone
  // low pass on the tension estimate: accelerometer noise (a few 0.01 N after m) and the
  // rate loop's thrust ripple are averaged over ~10 IMU samples
  double filter_time_constant_s = 0.02;
  // slack below this fraction of the hanging weight m_L g, taut again above taut_fraction;
  // an aggressive Lissajous keeps the tension above ~0.6 m_L g, a held payload near 0
  double slack_fraction = 0.25;
  double taut_fraction = 0.5;
};

/// Estimates the cable tension from IMU samples and says whether it is slack.
class TensionCue {
 public:
  /// Starts with the filtered tension at the hanging weight (taut) or zero (slack).
  TensionCue(const Params& params, const TensionCueConfig& config, bool start_slack);

  /// Feeds one IMU sample: bias-corrected specific force in the body frame, attitude, the
  /// collective thrust command and the cable direction xi (world). Returns slack(); non-finite
  /// or out-of-order inputs change nothing.
  bool Update(double time_s, const Eigen::Vector3d& specific_force_B_mps2,
              const Eigen::Matrix3d& R_WB, double thrust_command_N, const Eigen::Vector3d& xi_W);

  /// True while the filtered tension says the cable is slack (with hysteresis).
  bool slack() const { return slack_; }
  /// Filtered tension estimate (N).
  double tension_N() const { return tension_N_; }

 private:
  Params params_;
  TensionCueConfig config_;
  bool started_ = false;
  double last_time_s_ = 0.0;
  double thrust_N_;   // the command through the motors' first-order lag
  double tension_N_;  // filtered estimate
  bool slack_;
};

}  // namespace hpa
