#pragma once
// Geometric (Lee et al., SE(3)) baseline: tracks the flat quadrotor reference, treats the
// hanging payload's weight as a thrust feed-forward, and outputs body rates (attitude P loop,
// as PX4) plus collective thrust for the body-rate controller. 150 Hz.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>

#include "hpa/controller/controller.h"

namespace hpa {

/// Gains of the geometric controller (accelerations per metre, per m/s; rates per rad).
struct GeometricGains {
  Eigen::Vector3d k_position_per_s2{4.0, 4.0, 6.0};  // position error -> acceleration  (3)
  Eigen::Vector3d k_velocity_per_s{3.5, 3.5, 4.5};   // velocity error -> acceleration  (3)
  Eigen::Vector3d k_attitude_per_s{7.0, 7.0, 3.0};   // attitude error -> body rate  (3)
  double max_tilt_rad = 0.6;                         // commanded tilt limit (34 deg)
  double max_rate_radps = 6.0;                       // commanded body-rate limit
};

/// The cascade's last step, shared by the geometric and the team controllers: the collective
/// thrust F . R e3 of a desired force and the body rate -K_R e_R toward the attitude r_des, with
/// e_R = 1/2 vee(R_d^T R - R^T R_d) (Lee et al.), each rate clamped to +-max_rate_radps.
BodyRateCommand AttitudeCascadeCommand(const Eigen::Vector3d& force_W_N,
                                       const Eigen::Matrix3d& r_des, const Eigen::Quaterniond& q_WB,
                                       const Eigen::Vector3d& k_attitude_per_s,
                                       double max_rate_radps);

/// Lee-style SE(3) controller on the quadrotor with a payload feed-forward.
class GeometricController : public Controller {
 public:
  GeometricController(const Params& params, std::shared_ptr<const Reference> reference,
                      const GeometricGains& gains = GeometricGains());

  /// Desired force F = M_eff (a_ref - K_p e_p - K_v e_v) + feed-forward, where taut:
  /// M_eff = m + m_L and the feed-forward carries the payload, m (a_Q + g e3) + m_L (a_L + g e3);
  /// slack: M_eff = m and m (a_Q + g e3). Thrust = F . b3, rates = -K_R e_R (yaw 0).
  /// Non-finite state: kNonFinite and a level hover command.
  ControlOutput Update(const SystemState& state) override;
  double RateHz() const override { return 150.0; }

 private:
  Params params_;
  std::shared_ptr<const Reference> reference_;
  GeometricGains gains_;
};

}  // namespace hpa
