// A vehicle's actuation: motor lag, battery sag and the rotors' thrust into MuJoCo's actuators.

#include "hpa/sim/vehicle.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hpa/sim/faults.h"
#include "hpa/sim/world.h"

namespace hpa::sim {

Vehicle::Vehicle(const VehicleBinding& binding) : b_(binding) {
  if (b_.model == nullptr || b_.data == nullptr || b_.params == nullptr ||
      b_.actuation == nullptr || b_.step == nullptr || b_.t0_s == nullptr) {
    throw std::logic_error("sim::Vehicle: a binding without its world's model, data or clock");
  }
  for (int a : b_.rotor_actuator) {
    if (a < 0 || a >= b_.model->nu) throw std::logic_error("sim::Vehicle: no rotor actuator");
  }
}

double Vehicle::time_s() const { return *b_.t0_s + *b_.step * World::kPhysicsDt_s; }

void Vehicle::SetCommand(const InputVector& w_cmd_radps) {
  if (!w_cmd_radps.allFinite()) {
    throw std::invalid_argument("World::SetMotorSpeedCommand: non-finite motor speed command");
  }
  const Params& p = *b_.params;
  motor_command_radps_ =
      w_cmd_radps.cwiseMax(p.motor_speed_min_radps).cwiseMin(p.motor_speed_max_radps);
}

void Vehicle::SetSpeed(const InputVector& motor_speed_radps) {
  const Params& p = *b_.params;
  motor_speed_radps_ =
      motor_speed_radps.cwiseMax(p.motor_speed_min_radps).cwiseMin(p.motor_speed_max_radps);
  motor_command_radps_ = motor_speed_radps_;
}

void Vehicle::SetRotorFactors(const Eigen::Vector4d& thrust_factor,
                              const Eigen::Vector4d& torque_factor) {
  rotor_kf_factor_ = thrust_factor;
  rotor_km_factor_ = torque_factor;
}

void Vehicle::StepMotors() {
  // first-order motor lag, exact for the 1 ms step
  const double alpha = 1.0 - std::exp(-World::kPhysicsDt_s / b_.params->motor_time_constant_s);
  // (with battery sag the speed a command reaches falls with the pack voltage)
  const InputVector target_radps = b_.actuation->enabled
                                       ? InputVector(motor_command_radps_ * BatterySpeedFactor())
                                       : motor_command_radps_;
  motor_speed_radps_ += alpha * (target_radps - motor_speed_radps_);
}

void Vehicle::WriteMotorControls() {
  const Params& p = *b_.params;
  // a motor fault scales its rotor's thrust, down to zero (the actuator's lower bound with it)
  Eigen::Vector4d fault_factor;
  const bool motor_fault = b_.faults != nullptr && !b_.faults->empty() &&
                           b_.faults->MotorThrustFactors(time_s(), &fault_factor);
  for (int i = 0; i < 4; ++i) {
    const double w = motor_speed_radps_(i);
    const int a = b_.rotor_actuator[static_cast<size_t>(i)];
    b_.data->ctrl[a] = p.k_f_N_per_radps2 * rotor_kf_factor_(i) * w * w;
    if (!motor_fault) continue;
    b_.data->ctrl[a] *= fault_factor(i);
    const double w_min = p.motor_speed_min_radps;
    b_.model->actuator_ctrlrange[2 * a] =
        p.k_f_N_per_radps2 * rotor_kf_factor_(i) * w_min * w_min * fault_factor(i);
  }
}

double Vehicle::BatterySpeedFactor() const {
  const ActuationProfile& a = *b_.actuation;
  if (!a.enabled) return 1.0;
  return std::max(0.0, 1.0 - a.battery_voltage_drop_per_s * *b_.step * World::kPhysicsDt_s);
}

}  // namespace hpa::sim
