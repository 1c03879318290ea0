#pragma once
// PX4-like body-rate loop (500 Hz - 1 kHz): PID on body rate with gyroscopic feed-forward,
// then the rotor-speed allocation with thrust priority when the motors saturate.

#include <Eigen/Core>

#include "hpa/models/params.h"
#include "hpa/models/state.h"

namespace hpa {

/// Gains of the rate loop; moments are J * (Kp e + Ki int(e) - Kd d(w)/dt) + w x J w.
struct BodyRateGains {
  Eigen::Vector3d kp_per_s{25.0, 25.0, 12.0};            // proportional, 1/s  (3)
  Eigen::Vector3d ki_per_s2{40.0, 40.0, 20.0};           // integral, 1/s^2  (3)
  Eigen::Vector3d kd{0.0, 0.0, 0.0};                     // derivative on measurement  (3)
  Eigen::Vector3d integral_limit_radps2{8.0, 8.0, 4.0};  // clamp on Ki int(e), rad/s^2  (3)
};

/// What the last Update did.
struct BodyRateStatus {
  bool input_valid = true;    // false: a non-finite input was rejected, safe output sent
  bool saturated = false;     // true: moments were scaled down to respect the motor bounds
  double moment_scale = 1.0;  // factor applied to the moment demand (1 = unsaturated)
};

/// PID body-rate controller producing rotor speeds (rad/s).
class BodyRateController {
 public:
  /// Uses the flight parameters (inertia, rotor constants, motor bounds).
  explicit BodyRateController(const Params& params, const BodyRateGains& gains = BodyRateGains());

  /// One loop step: rotor speeds (rad/s, inside the motor bounds) tracking cmd.
  /// Non-finite cmd, measurement or dt: resets the loop and returns the speeds of a level
  /// hover wrench (HoverThrustN, zero moments), and status().input_valid becomes false.
  InputVector Update(const BodyRateCommand& cmd, const Eigen::Vector3d& w_B_measured_radps,
                     double dt_s);

  /// Clears the integrator and the derivative memory.
  void Reset();

  /// Status of the last Update.
  const BodyRateStatus& status() const { return status_; }

  /// Rotor speeds for a wrench [f, M] with thrust priority: f is clamped to what the motors
  /// can give, then the moments are scaled by the largest factor in [0, 1] that keeps every
  /// rotor inside its bounds. moment_scale (optional) receives that factor.
  static InputVector AllocateWithThrustPriority(const Params& params, const Eigen::Vector4d& wrench,
                                                double* moment_scale = nullptr);

 private:
  Params params_;
  BodyRateGains gains_;
  Eigen::Vector3d integral_radps2_ = Eigen::Vector3d::Zero();  // Ki int(e)  (3)
  Eigen::Vector3d w_prev_radps_ = Eigen::Vector3d::Zero();     // last measurement  (3)
  bool has_prev_ = false;
  BodyRateStatus status_;
};

}  // namespace hpa
