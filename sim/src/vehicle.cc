// The vehicle's actuation: motor lag, battery sag and the rotors' thrust into MuJoCo's actuators.

#include "hpa/sim/vehicle.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hpa/sim/world.h"

namespace hpa::sim {

void Vehicle::SetCommand(const InputVector& w_cmd_radps) {
  if (!w_cmd_radps.allFinite()) {
    throw std::invalid_argument("World::SetMotorSpeedCommand: non-finite motor speed command");
  }
  const Params& p = w_.world_params_;
  motor_command_radps_ =
      w_cmd_radps.cwiseMax(p.motor_speed_min_radps).cwiseMin(p.motor_speed_max_radps);
}

void Vehicle::SetSpeed(const InputVector& motor_speed_radps) {
  const Params& p = w_.world_params_;
  motor_speed_radps_ =
      motor_speed_radps.cwiseMax(p.motor_speed_min_radps).cwiseMin(p.motor_speed_max_radps);
  motor_command_radps_ = motor_speed_radps_;
}

void Vehicle::StepMotors() {
  // first-order motor lag, exact for the 1 ms step
  const double alpha =
      1.0 - std::exp(-World::kPhysicsDt_s / w_.world_params_.motor_time_constant_s);
  // (with battery sag the speed a command reaches falls with the pack voltage)
  const InputVector target_radps = w_.config_.profile.actuation.enabled
                                       ? InputVector(motor_command_radps_ * BatterySpeedFactor())
                                       : motor_command_radps_;
  motor_speed_radps_ += alpha * (target_radps - motor_speed_radps_);
}

void Vehicle::WriteMotorControls() {
  const Params& world_params_ = w_.world_params_;
  mjModel* model_ = w_.model_;
  mjData* data_ = w_.data_;
  // a motor fault scales its rotor's thrust, down to zero (the actuator's lower bound with it)
  Eigen::Vector4d fault_factor;
  const bool motor_fault =
      !w_.faults_.empty() && w_.faults_.MotorThrustFactors(w_.time_s(), &fault_factor);
  for (int i = 0; i < 4; ++i) {
    const double w = motor_speed_radps_(i);
    const int a = w_.ids_.rotor_actuator[i];
    data_->ctrl[a] = world_params_.k_f_N_per_radps2 * rotor_kf_factor_(i) * w * w;
    if (!motor_fault) continue;
    data_->ctrl[a] *= fault_factor(i);
    const double w_min = world_params_.motor_speed_min_radps;
    model_->actuator_ctrlrange[2 * a] =
        world_params_.k_f_N_per_radps2 * rotor_kf_factor_(i) * w_min * w_min * fault_factor(i);
  }
}

double Vehicle::BatterySpeedFactor() const {
  const ActuationProfile& a = w_.config_.profile.actuation;
  if (!a.enabled) return 1.0;
  return std::max(0.0, 1.0 - a.battery_voltage_drop_per_s * w_.step_ * World::kPhysicsDt_s);
}

}  // namespace hpa::sim
