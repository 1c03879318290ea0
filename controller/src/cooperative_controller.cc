// RotorTM's cable-suspended cooperative controller, one vehicle's share. Source:
// arplaboratory/RotorTM commit 069bddf, rotor_tm_control/src/rotor_tm_control/controller.py,
// cooperative_suspended_payload_controller (payload PD wrench, cable force distribution
// mu = diag(R) pinv(P) [R^T F; M], attachment accelerations) and cooperative_attitude_controller
// (cable-direction tracking, thrust F = Force . R e3, Rot_des from Force with yaw 0).
//
// Departures from RotorTM:
// - RotorTM's vehicle outputs a thrust and a moment (quadrotor_attitude_controller). Ours outputs
//   the thrust and a body rate for the vehicle's autopilot, the same cascade as
//   geometric_controller.cc: body rate = -K_R e_R toward Rot_des, because every vehicle in this
//   simulator flies through its autopilot's rate loop.
// - xi_dot is the cable direction's derivative, the relative velocity's part across the cable
//   divided by the cable's length (the paper's); RotorTM's controller_node.py passes the
//   relative velocity itself (its division by cable_len is commented out).
// - RotorTM assumes every cable taut. A vehicle that sees its cable slack holds the position
//   above its attachment point's reference at its cable length along the desired direction
//   (a PD with gravity compensation of its own mass, RotorTM's per-vehicle Kp, Kd).
// - The commanded force keeps a positive vertical component (as the geometric controller's)
//   and the body rate is clamped, so a wild state never commands an inverted attitude.

#include "hpa/controller/cooperative_controller.h"

#include <Eigen/Geometry>
#include <Eigen/QR>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "hpa/controller/geometric_controller.h"

namespace hpa {
namespace {

// The skew-symmetric matrix of v (v^ w = v x w).
Eigen::Matrix3d Hat(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// The vector of a skew-symmetric matrix (the inverse of Hat).
Eigen::Vector3d Vee(const Eigen::Matrix3d& m) { return Eigen::Vector3d(m(2, 1), m(0, 2), m(1, 0)); }

// RotorTM's desired attitude: b3 along the force, x_B = (e2 rotated by yaw) x b3, yaw 0.
Eigen::Matrix3d AttitudeFromForce(const Eigen::Vector3d& force_W_N) {
  const Eigen::Vector3d z = force_W_N.normalized();
  Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z);
  if (x.norm() < 1e-9) x = Eigen::Vector3d::UnitX();
  x.normalize();
  const Eigen::Vector3d y = z.cross(x).normalized();
  Eigen::Matrix3d r;
  r << x, y, z;
  return r;
}

}  // namespace

CooperativeController::CooperativeController(const CooperativeTeam& team, int vehicle,
                                             std::shared_ptr<const Reference> payload_reference,
                                             const CooperativeGains& gains)
    : team_(team), vehicle_(vehicle), reference_(std::move(payload_reference)), gains_(gains) {
  const int n = static_cast<int>(team_.vehicles.size());
  if (n < 1) throw std::invalid_argument("cooperative controller: empty team");
  if (vehicle < 0 || vehicle >= n) {
    throw std::invalid_argument("cooperative controller: vehicle " + std::to_string(vehicle) +
                                " outside a team of " + std::to_string(n));
  }
  if (!reference_) throw std::invalid_argument("cooperative controller: null reference");
  // read_params.py: P = [I I ...; rho_1^ rho_2^ ...] (6 x 3N), pinv_P = LA.pinv(P)
  Eigen::MatrixXd p(6, 3 * n);
  for (int i = 0; i < n; ++i) {
    p.block<3, 3>(0, 3 * i).setIdentity();
    p.block<3, 3>(3, 3 * i) = Hat(team_.vehicles[i].p_PA_P_m);
  }
  pinv_P_ = p.completeOrthogonalDecomposition().pseudoInverse();
}

Eigen::VectorXd CooperativeController::CableForcesN(const TeamView& view) const {
  return Demand(view, reference_->At(view.time_s)).mu_N;
}

CooperativeController::PayloadDemand CooperativeController::Demand(
    const TeamView& view, const ReferencePoint& ref) const {
  const Eigen::Matrix3d r_wp = view.q_WP.normalized().toRotationMatrix();
  const double m_l = team_.payload_mass_kg;
  const Eigen::Vector3d g_e3(0, 0, team_.gravity_mps2);

  // position control: F = m g e3 + m (a_des + Kp e_p + Kd e_v)
  const Eigen::Vector3d e_p = ref.p_WL_W - view.p_WL_W;
  const Eigen::Vector3d e_v = ref.v_WL_W - view.v_WL_W;
  const Eigen::Vector3d acc_des = ref.a_WL_W + gains_.k_payload_position_per_s2.cwiseProduct(e_p) +
                                  gains_.k_payload_velocity_per_s.cwiseProduct(e_v);
  const Eigen::Vector3d f_W_N = m_l * g_e3 + m_l * acc_des;

  // attitude control toward level (quat_des identity, omega_des 0): M = -Kpe e_R - Kde e_w
  const Eigen::Vector3d e_r = 0.5 * Vee(r_wp - r_wp.transpose());
  const Eigen::Vector3d m_P_Nm = -gains_.k_payload_attitude_Nm.cwiseProduct(e_r) -
                                 gains_.k_payload_rate_Nms.cwiseProduct(view.w_P);

  // distribution: mu = diag(R) pinv(P) [R^T F; M], vertical components clamped at 0
  Eigen::Matrix<double, 6, 1> wrench;
  wrench << r_wp.transpose() * f_W_N, m_P_Nm;
  Eigen::VectorXd mu = pinv_P_ * wrench;
  for (int i = 0; i < static_cast<int>(team_.vehicles.size()); ++i) {
    Eigen::Vector3d mu_i = r_wp * mu.segment<3>(3 * i);
    mu_i.z() = std::max(mu_i.z(), 0.0);
    mu.segment<3>(3 * i) = mu_i;
  }
  return {mu, acc_des};
}

ControlOutput CooperativeController::Update(const TeamView& view) {
  const auto start = std::chrono::steady_clock::now();
  const CooperativeVehicle& vehicle = team_.vehicles[vehicle_];
  const Params& params = vehicle.params;
  ControlOutput out;
  if (!AllFinite(view)) {
    out.status = ControlStatus::kNonFinite;
    out.command = LevelOutCommand(params, view.q_WB);
    return out;
  }
  const double m = params.quad_mass_kg;
  const double l = vehicle.cable_length_m;
  const Eigen::Vector3d g_e3(0, 0, params.gravity_mps2);
  const Eigen::Vector3d& rho = vehicle.p_PA_P_m;
  const Eigen::Matrix3d r_wp = view.q_WP.normalized().toRotationMatrix();
  const ReferencePoint ref = reference_->At(view.time_s);

  // the cable force this vehicle owes the payload and the desired cable direction
  const PayloadDemand demand = Demand(view, ref);
  const Eigen::Vector3d mu_i = demand.mu_N.segment<3>(3 * vehicle_);
  const Eigen::Vector3d xi_des =
      mu_i.norm() > 1e-9 ? Eigen::Vector3d(-mu_i.normalized()) : Eigen::Vector3d(0, 0, -1);

  // attachment point, its velocity, and the commanded acceleration plus gravity (att_acc_c)
  const Eigen::Vector3d p_WA_W = view.p_WL_W + r_wp * rho;
  const Eigen::Vector3d v_WA_W = view.v_WL_W + r_wp * view.w_P.cross(rho);
  const Eigen::Matrix3d w_hat = Hat(view.w_P);
  const Eigen::Vector3d a_att_W =
      demand.acc_des_mps2 + Eigen::Vector3d(0, 0, team_.gravity_mps2) + r_wp * w_hat * w_hat * rho;

  // cable direction xi (vehicle to attachment, RotorTM's) and the cable's reading
  const Eigen::Vector3d r_QA_W = p_WA_W - view.p_WQ_W;
  const double d_m = r_QA_W.norm();
  const Eigen::Vector3d xi = d_m > 1e-9 ? Eigen::Vector3d(r_QA_W / d_m) : Eigen::Vector3d(0, 0, -1);
  taut_ = d_m >= l - gains_.slack_band_m;

  Eigen::Vector3d force_W_N;
  if (taut_) {
    // cable-direction tracking (xi_des_dot = 0, so w_des = 0 and e_w = w)
    const Eigen::Vector3d v_rel = v_WA_W - view.v_WQ_W;
    const Eigen::Vector3d xi_dot = (v_rel - xi * xi.dot(v_rel)) / std::max(d_m, 1e-9);
    const Eigen::Vector3d w = xi.cross(xi_dot);
    const Eigen::Matrix3d xixi = xi * xi.transpose();
    const Eigen::Vector3d e_xi = xi_des.cross(xi);
    const Eigen::Vector3d e_w = w;
    const Eigen::Vector3d u_parallel =
        xixi * mu_i + m * l * w.squaredNorm() * xi + m * xixi * a_att_W;
    const Eigen::Vector3d u_perpendicular =
        -m * l *
            xi.cross(gains_.k_cable_direction_per_s2.cwiseProduct(e_xi) +
                     gains_.k_cable_rate_per_s.cwiseProduct(e_w)) -
        m * xi.cross(xi.cross(a_att_W));
    force_W_N = u_parallel + u_perpendicular;
  } else {
    // slack: hold the taut target, above the attachment point's reference along -xi_des
    const Eigen::Vector3d p_target_W = ref.p_WL_W + rho - l * xi_des;
    force_W_N = m * (ref.a_WL_W + g_e3 +
                     gains_.k_hold_position_per_s2.cwiseProduct(p_target_W - view.p_WQ_W) +
                     gains_.k_hold_velocity_per_s.cwiseProduct(ref.v_WL_W - view.v_WQ_W));
  }
  force_W_N.z() = std::max(force_W_N.z(), 0.2 * m * params.gravity_mps2);

  // thrust F = Force . R e3; body rate toward Rot_des (our autopilot cascade)
  out.command = AttitudeCascadeCommand(force_W_N, AttitudeFromForce(force_W_N), view.q_WB,
                                       gains_.k_attitude_per_s, gains_.max_rate_radps);
  out.status = ControlStatus::kSuccess;
  out.solve_time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace hpa
