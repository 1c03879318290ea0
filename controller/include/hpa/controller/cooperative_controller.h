#pragma once
// RotorTM's cable-suspended cooperative controller (docs/cooperative.md) as one vehicle's
// TeamController: the payload's PD wrench, its distribution over the cables, and this vehicle's
// cable-direction tracking, ending in a thrust and body-rate command for its autopilot.
// Source: arplaboratory/RotorTM commit 069bddf, rotor_tm_control/src/rotor_tm_control/
// controller.py (cooperative_suspended_payload_controller, cooperative_attitude_controller),
// rotor_tm_utils/src/rotor_tm_utils/read_params.py (gains, pinv(P)) and
// rotor_tm_control/src/rotor_tm_control/controller_node.py (qd_odom_callback: xi, xi_dot).

#include <Eigen/Core>
#include <memory>

#include "hpa/controller/team_controller.h"

namespace hpa {

/// Gains of the cooperative controller, RotorTM's defaults: the payload's from
/// rotor_tm_config/config/control_params/triangular_payload_cooperative_cable_gains.yaml
/// (read_payload_control_gains: diagonal Kp, Kd, Kpe, Kde), each vehicle's from
/// snapdragonfly_control_gains.yaml (read_uav_control_gains: Kxi, Kw, and Kp, Kd for the slack
/// position hold), the robot_list vehicle of RotorTM's 0.5 m cable teams
/// (attach_mechanism/cable/2_robots_long_bar_payload_0-5m.yaml,
/// 3_robots_triangular_payload_0-5m.yaml).
struct CooperativeGains {
  Eigen::Vector3d k_payload_position_per_s2{3.08, 3.08, 6.25};  // payload Kp ("pos")  (3)
  Eigen::Vector3d k_payload_velocity_per_s{2.15, 2.15, 3.42};   // payload Kd ("vel")  (3)
  Eigen::Vector3d k_payload_attitude_Nm{0.55, 0.50, 0.16};      // payload Kpe ("rot"), N m/rad (3)
  Eigen::Vector3d k_payload_rate_Nms{0.162, 0.162, 0.068};     // payload Kde ("ang"), N m s/rad (3)
  Eigen::Vector3d k_cable_direction_per_s2{16.0, 16.0, 16.0};  // vehicle Kxi ("xi")  (3)
  Eigen::Vector3d k_cable_rate_per_s{6.7, 6.7, 3.1};           // vehicle Kw ("omg")  (3)
  Eigen::Vector3d k_hold_position_per_s2{6.0, 6.0, 10.0};      // vehicle Kp ("pos"), slack  (3)
  Eigen::Vector3d k_hold_velocity_per_s{3.0, 3.0, 6.0};        // vehicle Kd ("vel"), slack  (3)
  // the autopilot cascade's attitude loop toward Rot_des: RotorTM's attitude PD of the vehicle
  // (snapdragonfly "rot" Kpe over "ang" Kde, M = -Kpe e_R - Kde e_w) as the body rate that
  // zeroes its moment, w = -(Kpe / Kde) e_R, for a rate loop faster than the attitude loop
  Eigen::Vector3d k_attitude_per_s{10.0, 10.0, 16.0};  // attitude error -> body rate  (3)
  double max_rate_radps = 6.0;                      // commanded body-rate limit
  double slack_band_m = 0.01;  // a cable shorter than its length by this is slack
  // RotorTM's controller rate: controller_node.py runs the controller on every desired-trajectory
  // message (desired_traj_callback -> sim_subscriber), which traj_node.py publishes at
  // rospy.Rate(100), the rate simulation_base.py steps the plant at (self.rate = 100)
  double rate_hz = 100.0;
};

/// Vehicle `vehicle`'s share of RotorTM's cooperative controller. Every vehicle runs the same
/// payload controller on the same payload state and team geometry, so each computes the whole
/// distribution and keeps its own cable's force.
class CooperativeController : public TeamController {
 public:
  /// Throws std::invalid_argument for an empty team, a vehicle out of range or a null reference.
  CooperativeController(const CooperativeTeam& team, int vehicle,
                        std::shared_ptr<const Reference> payload_reference,
                        const CooperativeGains& gains = CooperativeGains());

  /// Taut: RotorTM's cable-direction tracking to the distributed cable force; slack: a position
  /// hold above the attachment point at the cable's length along the desired direction.
  ControlOutput Update(const TeamView& view) override;
  /// The last Update's reading: distance to the attachment >= cable length - slack_band_m.
  bool CableTaut() const override { return taut_; }
  /// CooperativeGains::rate_hz.
  double RateHz() const override { return gains_.rate_hz; }

  /// The cable forces on the payload (world, 3N, vehicle by vehicle) for the payload's state and
  /// reference at view.time_s, negative vertical components clamped to 0 (RotorTM's mu).
  Eigen::VectorXd CableForcesN(const TeamView& view) const;

 private:
  // The payload controller's outputs: the cable forces (world, 3N) and the payload's commanded
  // acceleration (acceleration_des, world).
  struct PayloadDemand {
    Eigen::VectorXd mu_N;
    Eigen::Vector3d acc_des_mps2;
  };
  PayloadDemand Demand(const TeamView& view, const ReferencePoint& ref) const;

  CooperativeTeam team_;
  int vehicle_;
  std::shared_ptr<const Reference> reference_;
  CooperativeGains gains_;
  Eigen::MatrixXd pinv_P_;  // pinv([I I ...; rho_1^ rho_2^ ...])  (3N x 6)
  bool taut_ = true;
};

}  // namespace hpa
