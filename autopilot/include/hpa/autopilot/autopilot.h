#pragma once
// The autopilot: the vehicle's inner loop between a flight stack's body-rate + thrust command and
// its rotors, as a flight controller board runs it beside (or under) a companion computer's
// flight stack. Two are built in: the project's own body-rate loop on the estimated body rate at
// the IMU's rate, and PX4's rate loop on each sample of the vehicle's rate gyro. The simulator
// runs the scenario's autopilot for whichever flight stack flies, in process or external, unless
// an external stack owns the rate loop (docs/protocol.md, rate_tick and rate_reply): then the
// stack runs it (hpa-flight --own-rate-loop runs this one). Flight code: no MuJoCo, no GL.

#include <Eigen/Core>
#include <memory>

#include "hpa/autopilot/body_rate_controller.h"
#include "hpa/autopilot/px4_rate_controller.h"
#include "hpa/models/params.h"
#include "hpa/models/state.h"

namespace hpa {

/// Which rate loop a vehicle flies, from the world profile's `rate_loop` section: the project's
/// own loop on the estimated body rate (px4 false), or PX4's rate controller with these
/// parameters on the vehicle's rate gyro (px4 true).
struct RateLoopSpec {
  bool px4 = false;
  Px4RateParams params;
};

/// One step of the autopilot: the rotor speed commands and what the allocation made of the
/// command (the thrust the flight stack's estimator is told).
struct AutopilotOutput {
  InputVector w_cmd_radps = InputVector::Zero();  // rotor speed commands  (4)
  double thrust_allocated_N = 0.0;                // collective thrust of those speeds
  bool saturated = false;                         // the allocation fell short of the command
};

/// The inner loop from body-rate command to rotor speeds.
class Autopilot {
 public:
  virtual ~Autopilot() = default;
  /// True: it runs on each sample of the vehicle's rate gyro (its own clock); false: on the
  /// estimated body rate at the rate the caller gave MakeAutopilot.
  virtual bool RunsOnGyro() const = 0;
  /// One step toward `command` at the measured body rate `w_B_radps`.
  virtual AutopilotOutput Update(const BodyRateCommand& command,
                                 const Eigen::Vector3d& w_B_radps) = 0;
};

/// The autopilot `spec` names for a vehicle with flight params `params`; the own loop steps at
/// `rate_hz`.
std::unique_ptr<Autopilot> MakeAutopilot(const Params& params, const RateLoopSpec& spec,
                                         double rate_hz);

}  // namespace hpa
