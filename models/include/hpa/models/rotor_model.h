#pragma once
// Rotor geometry and the rotor-speed-to-wrench map (X configuration).

#include <Eigen/Core>

#include "hpa/models/params.h"
#include "hpa/models/state.h"

namespace hpa {

/// Rotor i sits at RotorPosition(i) in the body frame and spins with direction RotorSpin(i):
/// rotors 0..3 at (+x+y), (-x+y), (-x-y), (+x-y) / sqrt(2) * arm; spin +1 makes a reaction
/// torque +k_m w^2 about body z.
Eigen::Vector3d RotorPosition_B(const Params& params, int i);
/// +1 or -1 (reaction torque sign about body z) for rotor i.
double RotorSpin(int i);

/// Maps rotor thrusts [f_0..f_3] (N) to the body wrench [f (N), M_x, M_y, M_z (N m)].
Eigen::Matrix4d AllocationMatrix(const Params& params);

/// Rotor speeds (rad/s) to the body wrench [f, M_x, M_y, M_z] through f_i = k_f w_i^2.
Eigen::Vector4d WrenchFromRotorSpeeds(const Params& params, const InputVector& w_radps);

/// Inverse map: rotor speeds that produce the wrench, clamped to the motor bounds.
InputVector RotorSpeedsFromWrench(const Params& params, const Eigen::Vector4d& wrench);

}  // namespace hpa
