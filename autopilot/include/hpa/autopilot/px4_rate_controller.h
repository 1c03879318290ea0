#pragma once
// PX4's multicopter rate loop (mc_rate_control with src/lib/rate_control) and its control
// allocation with airmode disabled (control_allocator, ControlAllocationSequentialDesaturation),
// on this vehicle: the gyro is low-passed (IMU_GYRO_CUTOFF) and differentiated with its own
// low-pass (IMU_DGYRO_CUTOFF), a PID in normalised torque with derivative on the measurement and
// an integrator that stops growing in the direction the allocation saturated, a first-order
// low-pass on the yaw torque (MC_YAW_TQ_CUTOFF), and the sequential desaturation that keeps roll
// and pitch, lowers the thrust and gives yaw the lowest priority.
//
// Normalised torque and thrust. PX4 allocates on normalised actuators u in [0, 1]; here u is the
// rotor thrust f = f_min + u (f_max - f_min), f = k_f w^2 (PX4's thrust model with THR_MDL_FAC
// matched to the rotor: thrust linear in u). PX4 normalises the pseudo-inverse of the
// effectiveness: roll and pitch columns to |col|^2 = n / 2 (ControlAllocationPseudoInverse::
// updateControlAllocationMatrixScale), yaw and thrust columns to a largest entry of 1. For four
// rotors at (+-a/sqrt(2), +-a/sqrt(2)) that makes a unit roll or pitch torque +-1/sqrt(2) of the
// thrust range on each rotor, i.e. 2 a (f_max - f_min) N m; a unit yaw torque +-1 on each rotor,
// 4 (k_m / k_f) (f_max - f_min) N m; a unit thrust 4 (f_max - f_min) N. With models/params.yaml
// (a = 0.15 m, k_f = 1.5e-6, k_m = 2.4e-8, w in [100, 1830] rad/s: f in [0.015, 5.023] N) these
// are 1.502 N m, 0.3205 N m and 20.03 N. Px4TorqueScale computes them from the parameters.

#include <Eigen/Core>

#include "hpa/autopilot/butterworth_low_pass.h"
#include "hpa/models/param_table.h"
#include "hpa/models/params.h"
#include "hpa/models/state.h"

namespace hpa {

/// PX4 rate-loop parameters (PX4 names in the comments; defaults are PX4's defaults).
struct Px4RateParams {
  double rate_hz = 1000.0;               // loop and gyro rate (PX4 runs it on each gyro sample), Hz
  Eigen::Vector3d p{0.15, 0.15, 0.2};    // MC_ROLLRATE_P, MC_PITCHRATE_P, MC_YAWRATE_P: 1/(rad/s)
  Eigen::Vector3d i{0.2, 0.2, 0.1};      // MC_*RATE_I: normalised torque per rad of error  (3)
  Eigen::Vector3d d{0.003, 0.003, 0.0};  // MC_*RATE_D: normalised torque per rad/s^2  (3)
  Eigen::Vector3d k{1.0, 1.0, 1.0};      // MC_*RATE_K: scales P, I and D  (3)
  Eigen::Vector3d integrator_limit{0.3, 0.3, 0.3};  // MC_RR_INT_LIM, MC_PR_INT_LIM, MC_YR_INT_LIM
  double gyro_cutoff_hz = 30.0;       // IMU_GYRO_CUTOFF: 2nd-order Butterworth on the gyro
  double dgyro_cutoff_hz = 30.0;      // IMU_DGYRO_CUTOFF: 2nd-order Butterworth on d(gyro)/dt
  double yaw_torque_cutoff_hz = 2.0;  // MC_YAW_TQ_CUTOFF: first-order low-pass on yaw torque
  double yaw_headroom = 0.15;         // mixYaw: yaw may push actuators 15 % past their maximum
};

/// The PX4 parameters of Px4RateParams as a scenario sets them (the world profile's `rate_loop`
/// section): YAML key, unit, the range of PX4's parameter declarations per axis
/// (mc_rate_control_params.c's @min/@max; a generous bound where PX4 gives no @max), meaning.
/// Flight-code parameters, declared once here: their values are Px4RateParams' defaults.
const ParamTable<Px4RateParams>& Px4RateParamTable();

/// Physical size of a unit normalised command: N m per unit roll, pitch, yaw torque and N per
/// unit collective thrust (see the file comment).
struct Px4TorqueScale {
  Eigen::Vector3d torque_Nm = Eigen::Vector3d::Zero();  // roll, pitch, yaw  (3)
  double thrust_N = 0.0;                                // collective
};

/// What the last Update did.
struct Px4RateStatus {
  bool input_valid = true;  // false: a non-finite input was rejected, the safe output sent
  Eigen::Vector3d torque_sp = Eigen::Vector3d::Zero();         // normalised torque demand  (3)
  Eigen::Vector3d torque_allocated = Eigen::Vector3d::Zero();  // what the rotors give  (3)
  double thrust_sp = 0.0;           // normalised collective thrust demand
  double thrust_allocated = 0.0;    // normalised collective thrust the rotors give
  double thrust_allocated_N = 0.0;  // the same in N (what the flight code knows it makes)
  bool saturated = false;           // the allocation gave less thrust or torque than demanded
  Eigen::Vector3d integral = Eigen::Vector3d::Zero();  // integrator, normalised torque  (3)
  Eigen::Matrix<bool, 3, 1> saturated_positive = Eigen::Matrix<bool, 3, 1>::Constant(false);
  Eigen::Matrix<bool, 3, 1> saturated_negative = Eigen::Matrix<bool, 3, 1>::Constant(false);
};

/// Result of the airmode-disabled allocation.
struct Px4Allocation {
  Eigen::Vector4d u = Eigen::Vector4d::Zero();       // normalised rotor thrusts in [0, 1]  (4)
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();  // normalised torque they give  (3)
  double thrust = 0.0;                               // normalised collective thrust they give
};

/// PX4-like rate loop: gyro sample and (body rate, thrust) setpoint in, rotor speeds out.
class Px4RateController {
 public:
  /// Uses the flight parameters (rotor geometry, k_f, k_m, motor bounds).
  Px4RateController(const Params& params, const Px4RateParams& px4);

  /// One loop step on a raw gyro sample (rad/s, body frame) taken 1 / rate_hz after the last:
  /// rotor speeds (rad/s, inside the motor bounds). A non-finite command or gyro resets the loop
  /// and returns the speeds of the hover thrust with zero torque; status().input_valid is false.
  InputVector Update(const BodyRateCommand& cmd, const Eigen::Vector3d& gyro_B_radps);

  /// Clears the filters, the integrator, the saturation flags and the yaw torque filter.
  void Reset();
  /// Status of the last Update.
  const Px4RateStatus& status() const { return status_; }
  /// The normalisation of torque and thrust on this vehicle.
  const Px4TorqueScale& scale() const { return scale_; }

  /// The normalisation from the parameters (PX4's pseudo-inverse scaling; file comment).
  static Px4TorqueScale TorqueScale(const Params& params);
  /// PX4's mixAirmodeDisabled on this vehicle: normalised torque (roll, pitch, yaw) and thrust
  /// to normalised rotor thrusts in [0, 1]. Thrust is only ever lowered to unsaturate; roll and
  /// pitch are then scaled; yaw is added last and scaled to fit (yaw_headroom), then thrust is
  /// lowered again if yaw pushed a rotor past its maximum; the result is clipped to [0, 1].
  static Px4Allocation AllocateAirmodeDisabled(const Params& params, const Eigen::Vector3d& torque,
                                               double thrust, double yaw_headroom);
  /// Rotor speeds (rad/s) of normalised rotor thrusts u in [0, 1].
  static InputVector RotorSpeeds(const Params& params, const Eigen::Vector4d& u);

 private:
  Params params_;
  Px4RateParams px4_;
  Px4TorqueScale scale_;
  ButterworthLowPass gyro_filter_;
  ButterworthLowPass dgyro_filter_;
  Eigen::Vector3d gyro_prev_radps_ = Eigen::Vector3d::Zero();  // last raw gyro sample  (3)
  bool has_prev_ = false;
  Eigen::Vector3d integral_ = Eigen::Vector3d::Zero();  // normalised torque  (3)
  double yaw_torque_filtered_ = 0.0;                    // after MC_YAW_TQ_CUTOFF
  Eigen::Matrix<bool, 3, 1> sat_pos_ = Eigen::Matrix<bool, 3, 1>::Constant(false);  // last alloc
  Eigen::Matrix<bool, 3, 1> sat_neg_ = Eigen::Matrix<bool, 3, 1>::Constant(false);  // last alloc
  Px4RateStatus status_;
};

}  // namespace hpa
