#pragma once
// The vehicle's actuation (a component of sim::World): four first-order motors, each rotor's
// thrust and torque coefficients (the profile's per-vehicle spread) and the battery's sag; the
// rotor thrust written into MuJoCo's actuators each step. The runner commands it through
// World::SetMotorSpeedCommand.

#include <Eigen/Core>

#include "hpa/models/state.h"

namespace hpa::sim {

class World;

/// The quadrotor's motors and rotors as the world simulates them.
class Vehicle {
 public:
  /// Thrust coefficient of each rotor relative to the world's k_f (actuation spread)  (4)
  const Eigen::Vector4d& rotor_thrust_factor() const { return rotor_kf_factor_; }
  /// Rotor speed reached per unit command now (battery sag; 1 with a full pack or no sag).
  double BatterySpeedFactor() const;
  /// Actual (lagged) rotor speeds now (rad/s)  (4)
  const InputVector& motor_speed_radps() const { return motor_speed_radps_; }

 private:
  friend class World;
  explicit Vehicle(World& world) : w_(world) {}
  // new command, clamped to the motor bounds (non-finite: std::invalid_argument)
  void SetCommand(const InputVector& w_cmd_radps);
  // actual speeds and command set at once, clamped to the motor bounds (World::SetState)
  void SetSpeed(const InputVector& motor_speed_radps);
  // one step of the first-order motor lag towards the command (battery sag applied)
  void StepMotors();
  // rotor thrust into the actuators, a motor fault's factor applied
  void WriteMotorControls();

  World& w_;                                                   // the world this vehicle flies in
  InputVector motor_speed_radps_ = InputVector::Zero();        // actual (4)
  InputVector motor_command_radps_ = InputVector::Zero();      // commanded, clamped (4)
  Eigen::Vector4d rotor_kf_factor_ = Eigen::Vector4d::Ones();  // per-rotor k_f spread  (4)
  Eigen::Vector4d rotor_km_factor_ = Eigen::Vector4d::Ones();  // per-rotor k_m spread  (4)
};

}  // namespace hpa::sim
