#pragma once
// The interface every high-level controller (hpa_mpc, nonhybrid_mpc, geometric) offers the
// runner, and the factory that builds one from a scenario's controller block.

#include <memory>
#include <string>

#include "hpa/controller/controller_settings.h"
#include "hpa/controller/reference.h"
#include "hpa/models/param_table.h"
#include "hpa/models/params.h"
#include "hpa/models/state.h"

namespace hpa {

/// What happened in one controller update (acados-style status codes).
enum class ControlStatus {
  kSuccess,
  kMaxIterations,
  kQpFailure,
  kNonFinite,
  kFallback,
  kRecovery,  // tumbling: a safe recovery command instead of a plan (not a failure)
};

/// Name of a status for logs.
const char* ToString(ControlStatus status);

/// One controller update's result; `command` is always safe to fly.
struct ControlOutput {
  BodyRateCommand command;  // body rates and collective thrust for the rate loop
  ControlStatus status = ControlStatus::kSuccess;
  double solve_time_ms = 0.0;  // wall time of this update
  double cost = 0.0;           // optimal-control cost of the plan (0 if not an MPC)
};

/// A scenario's `controller:` block: which registered controller flies, and the settings the
/// scenario wrote for it (each controller declares its own: controller_settings.h).
struct ControllerConfig {
  std::string type = "hpa_mpc";  // a registered controller (controller_registry.h)
  ControllerSettings settings;   // by key; the flown controller reads the keys it declares

  /// The number `key` the flown controller declares (its default when not written); throws
  /// std::invalid_argument when `type` declares no number `key`.
  double Number(const std::string& key) const;
  /// The switch `key`, as Number.
  bool Switch(const std::string& key) const;
  /// The name `key`, as Number.
  std::string Name(const std::string& key) const;
};

/// A high-level controller running at its own rate (150 Hz for the MPCs).
class Controller {
 public:
  virtual ~Controller() = default;
  /// Computes the command from the (estimated or true) state at time state.time_s.
  virtual ControlOutput Update(const SystemState& state) = 0;
  /// Rate the runner should call Update at.
  virtual double RateHz() const = 0;
};

/// PX4's attitude gain MC_ROLL_P / MC_PITCH_P (default), 1/s: the level-out's.
constexpr double kPx4AttitudeGainPerS = 6.5;

/// The command every controller flies when it has no usable state or plan: PX4's attitude loop
/// toward level (body rate = gain x the tilt error, yaw left alone) at hover thrust; zero body
/// rate when q_WB is not finite.
BodyRateCommand LevelOutCommand(const Params& params, const Eigen::Quaterniond& q_WB,
                                double attitude_gain_per_s = kPx4AttitudeGainPerS);

/// Builds the controller named in config.type; throws std::invalid_argument for unknown types.
std::unique_ptr<Controller> MakeController(const ControllerConfig& config, const Params& params,
                                           std::shared_ptr<const Reference> reference);

}  // namespace hpa
