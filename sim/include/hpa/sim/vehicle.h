#pragma once
// A vehicle's actuation, alone (sim::World) or in a team (sim::TeamWorld): four first-order
// motors, each rotor's thrust and torque coefficients (the profile's per-vehicle spread) and the
// battery's sag; the rotor thrust written into MuJoCo's actuators each step. The world that owns
// it binds it to its own rotors (VehicleBinding) and steps it; it reaches nothing else of that
// world.

#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "hpa/models/params.h"
#include "hpa/models/state.h"
#include "hpa/sim/world_profile.h"

// MuJoCo's model and data, only pointed to here (sim/src includes MuJoCo)
struct mjModel_;
struct mjData_;

namespace hpa::sim {

class Faults;

/// What a Vehicle reaches of the world it flies in, filled by that world: its own rotors'
/// actuators in MuJoCo's model and data, the numbers the world simulates for it, the actuation
/// realism and the faults that act on it, and the world's clock. Every pointer outlives the
/// vehicle (the world owns them all).
struct VehicleBinding {
  mjModel_* model = nullptr;                          // the world's MuJoCo model
  mjData_* data = nullptr;                            // the world's MuJoCo data
  std::array<int, 4> rotor_actuator{{-1, -1, -1, -1}};  // its rotors' actuator ids  (4)
  const Params* params = nullptr;                     // its simulated numbers (mismatch applied)
  const ActuationProfile* actuation = nullptr;        // spread and battery sag (disabled: ideal)
  const Faults* faults = nullptr;                     // motor faults on it (null: none)
  const int64_t* step = nullptr;                      // the world's physics steps since Reset
  const double* t0_s = nullptr;                       // the world's time at Reset (s)
};

/// A quadrotor's motors and rotors as a world simulates them.
class Vehicle {
 public:
  /// Bound to a world's rotors; every pointer of the binding must be set but `faults`.
  explicit Vehicle(const VehicleBinding& binding);

  /// Thrust coefficient of each rotor relative to the world's k_f (actuation spread)  (4)
  const Eigen::Vector4d& rotor_thrust_factor() const { return rotor_kf_factor_; }
  /// Yaw torque coefficient of each rotor relative to the world's k_m (actuation spread)  (4)
  const Eigen::Vector4d& rotor_torque_factor() const { return rotor_km_factor_; }
  /// Rotor speed reached per unit command now (battery sag; 1 with a full pack or no sag).
  double BatterySpeedFactor() const;
  /// Actual (lagged) rotor speeds now (rad/s)  (4)
  const InputVector& motor_speed_radps() const { return motor_speed_radps_; }
  /// Commanded rotor speeds, clamped to the motor bounds (rad/s)  (4)
  const InputVector& motor_command_radps() const { return motor_command_radps_; }

  // What the owning world calls, in its step order.
  /// New command, clamped to the motor bounds (non-finite: std::invalid_argument).
  void SetCommand(const InputVector& w_cmd_radps);
  /// Actual speeds and command set at once, clamped to the motor bounds (a Reset or SetState).
  void SetSpeed(const InputVector& motor_speed_radps);
  /// The per-rotor coefficient spread (the profile's draw; ones: none).
  void SetRotorFactors(const Eigen::Vector4d& thrust_factor, const Eigen::Vector4d& torque_factor);
  /// One step of the first-order motor lag towards the command (battery sag applied).
  void StepMotors();
  /// Rotor thrust into the actuators, a motor fault's factor applied.
  void WriteMotorControls();

 private:
  double time_s() const;  // the world's time now

  VehicleBinding b_;                                           // the world it flies in
  InputVector motor_speed_radps_ = InputVector::Zero();        // actual (4)
  InputVector motor_command_radps_ = InputVector::Zero();      // commanded, clamped (4)
  Eigen::Vector4d rotor_kf_factor_ = Eigen::Vector4d::Ones();  // per-rotor k_f spread  (4)
  Eigen::Vector4d rotor_km_factor_ = Eigen::Vector4d::Ones();  // per-rotor k_m spread  (4)
};

}  // namespace hpa::sim
