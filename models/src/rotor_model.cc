#include "hpa/models/rotor_model.h"

#include <algorithm>
#include <cmath>

namespace hpa {

Eigen::Vector3d RotorPosition_B(const Params& params, int i) {
  static constexpr double kSigns[4][2] = {{1, 1}, {-1, 1}, {-1, -1}, {1, -1}};
  const double a = params.arm_length_m / std::sqrt(2.0);
  return Eigen::Vector3d(kSigns[i][0] * a, kSigns[i][1] * a, 0.0);
}

double RotorSpin(int i) { return (i % 2 == 0) ? 1.0 : -1.0; }

Eigen::Matrix4d AllocationMatrix(const Params& params) {
  Eigen::Matrix4d a;
  const double torque_per_thrust_m = params.k_m_Nm_per_radps2 / params.k_f_N_per_radps2;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d r = RotorPosition_B(params, i);
    // moment of a thrust f along body z at r: r x (0, 0, f) = (r_y f, -r_x f, 0)
    a.col(i) << 1.0, r.y(), -r.x(), RotorSpin(i) * torque_per_thrust_m;
  }
  return a;
}

Eigen::Vector4d WrenchFromRotorSpeeds(const Params& params, const InputVector& w_radps) {
  const Eigen::Vector4d f = params.k_f_N_per_radps2 * w_radps.array().square();
  return AllocationMatrix(params) * f;
}

InputVector RotorSpeedsFromWrench(const Params& params, const Eigen::Vector4d& wrench) {
  const Eigen::Vector4d f = AllocationMatrix(params).inverse() * wrench;
  InputVector w;
  for (int i = 0; i < 4; ++i) {
    const double w_sq = std::max(0.0, f(i)) / params.k_f_N_per_radps2;
    w(i) = std::clamp(std::sqrt(w_sq), params.motor_speed_min_radps, params.motor_speed_max_radps);
  }
  return w;
}

}  // namespace hpa
