// The cooperative model (hpa::CooperativeModel) against an independent, line-by-line transcription
// of RotorTM's cooperative cable-suspended payload simulator (arplaboratory/RotorTM,
// rotor_tm_sim/src/rotor_tm_sim/simulation_base.py:
// hybrid_cooperative_rigidbody_pl_transportationEOM, rigidbody_payloadEOM_readonly,
// taut_quadEOM_readonly, slack_quadEOM_readonly, rigidbody_quad_inelastic_cable_collision;
// rotor_tm_utils/utilslib.py: QuatToRot, quat_dot, vec2asym; rotor_tm_utils/read_params.py: P), and
// against HybridModel for N = 1.
#include "hpa/models/cooperative_model.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstdio>
#include <random>

#include "hpa/models/hybrid_model.h"
#include "hpa/models/rotor_model.h"

namespace hpa {
namespace {

using Eigen::Matrix3d;
using Eigen::MatrixXd;
using Eigen::Vector3d;
using Eigen::VectorXd;
using I = CooperativeStateIndex;

// ---------------------------------------------------------------------------------------------
// RotorTM, transcribed as its Python reads (numpy arrays as Eigen, names kept). Its simulator
// object keeps the payload's last accelerations (self.pl_accel, self.pl_ang_accel) and uses them
// in the tension; the payload's own accelerations do not depend on them, so a second call on the
// same state is RotorTM's consistent derivative.

// utilslib.vec2asym
Matrix3d vec2asym(const Vector3d& vec) {
  Matrix3d mat;
  mat << 0, -vec[2], vec[1], vec[2], 0, -vec[0], -vec[1], vec[0], 0;
  return mat;
}

// utilslib.QuatToRot
Matrix3d QuatToRot(Eigen::Vector4d q) {
  q = q / std::sqrt(q.array().square().sum());
  Matrix3d qahat = Matrix3d::Zero();
  qahat(0, 1) = -q[3];
  qahat(0, 2) = q[2];
  qahat(1, 2) = -q[1];
  qahat(1, 0) = q[3];
  qahat(2, 0) = -q[2];
  qahat(2, 1) = q[1];
  return Matrix3d::Identity() + 2 * qahat * qahat + 2 * q[0] * qahat;
}

// utilslib.quat_dot
Eigen::Vector4d quat_dot(const Eigen::Vector4d& quat, const Vector3d& omg) {
  const double qW = quat[0], qX = quat[1], qY = quat[2], qZ = quat[3];
  const double p = omg[0], q = omg[1], r = omg[2];
  const double K_quat = 2;
  const double quaterror = 1 - (qW * qW + qX * qX + qY * qY + qZ * qZ);
  Eigen::Matrix4d m;
  m << 0, -p, -q, -r, p, 0, r, -q, q, -r, 0, p, r, q, -p, 0;
  return 1.0 / 2 * m * quat + K_quat * quaterror * quat;
}

struct RotorTmUav {
  double mass, grav;
  Matrix3d I, invI;
};

struct RotorTmSimulation {
  int nquad;
  int pl_dim_num = 13, uav_dim_num = 13;
  double pl_mass, pl_grav;
  Matrix3d pl_I, pl_invI;
  MatrixXd P;             // read_params.py: vstack(identity_stack_mat, rho_vec_asym_mat)
  MatrixXd rho_vec_list;  // 3 x nquad
  VectorXd cable_len_list;
  std::vector<RotorTmUav> uav_params;
  std::vector<bool> cable_is_slack;
  VectorXd uav_F;  // nquad
  MatrixXd uav_M;  // 3 x nquad
  bool sim_start = false;
  Vector3d pl_accel, pl_ang_accel;
  Vector3d ext_force = Vector3d::Zero(), ext_torque = Vector3d::Zero();

  // rigidbody_payloadEOM_readonly
  VectorXd rigidbody_payloadEOM_readonly(const VectorXd& s, const Vector3d& F, const Vector3d& M,
                                         const Matrix3d& invML, const Matrix3d& C,
                                         const Matrix3d& D, const Matrix3d& E) {
    const Eigen::Vector4d quat = s.segment<4>(6);
    const Vector3d omega = s.segment<3>(10);
    const Eigen::Vector4d qLdot = quat_dot(quat, omega);
    const Vector3d effective_M = M - C * (invML * F) - omega.cross(pl_I * omega);
    const Matrix3d effective_inertia = pl_I + C * (invML * D) - E;
    const Vector3d omgLdot =
        effective_inertia.fullPivLu().solve(effective_M) + pl_invI * ext_torque;
    const Vector3d accL = invML * (F + D * omgLdot) - Vector3d(0, 0, pl_grav) + ext_force / pl_mass;
    VectorXd sdotLoad = VectorXd::Zero(pl_dim_num);
    sdotLoad.segment<3>(0) = s.segment<3>(3);
    sdotLoad.segment<3>(3) = accL;
    sdotLoad.segment<4>(6) = qLdot;
    sdotLoad.segment<3>(10) = omgLdot;
    return sdotLoad;
  }

  // taut_quadEOM_readonly (T: the tension vector)
  VectorXd taut_quadEOM_readonly(const VectorXd& qd, double F, const Vector3d& M, const Vector3d& T,
                                 int uav_idx) {
    const Vector3d vel = qd.segment<3>(3);
    const Eigen::Vector4d quat = qd.segment<4>(6);
    const Vector3d omega = qd.segment<3>(10);
    const Matrix3d R = QuatToRot(quat);
    const RotorTmUav& uav = uav_params[uav_idx];
    const Vector3d accel = (R * Vector3d(0, 0, F) + T) / uav.mass - Vector3d(0, 0, uav.grav);
    const Eigen::Vector4d qdot = quat_dot(quat, omega);
    const Vector3d pqrdot = uav.invI * (M - omega.cross(uav.I * omega));
    VectorXd sdot(uav_dim_num);
    sdot << vel, accel, qdot, pqrdot;
    return sdot;
  }

  // slack_quadEOM_readonly
  VectorXd slack_quadEOM_readonly(const VectorXd& qd, double F, const Vector3d& M, int uav_idx) {
    const Vector3d vel = qd.segment<3>(3);
    const Eigen::Vector4d quat = qd.segment<4>(6);
    const Vector3d omega = qd.segment<3>(10);
    const Matrix3d R = QuatToRot(quat);
    const RotorTmUav& uav = uav_params[uav_idx];
    const Vector3d accel = R * Vector3d(0, 0, F) / uav.mass - Vector3d(0, 0, uav.grav);
    const Eigen::Vector4d qdot = quat_dot(quat, omega);
    const Vector3d pqrdot = uav.invI * (M - omega.cross(uav.I * omega));
    VectorXd sdot(uav_dim_num);
    sdot << vel, accel, qdot, pqrdot;
    return sdot;
  }

  // hybrid_cooperative_rigidbody_pl_transportationEOM
  VectorXd hybrid_cooperative_rigidbody_pl_transportationEOM(double /*t*/, const VectorXd& s) {
    if (!sim_start) {
      pl_accel.setZero();
      pl_ang_accel.setZero();
      sim_start = true;
    }
    const VectorXd pl_state = s.head(pl_dim_num);
    const Vector3d pl_pos = pl_state.segment<3>(0);
    const Vector3d pl_vel = pl_state.segment<3>(3);
    const Eigen::Vector4d pl_quat = pl_state.segment<4>(6);
    const Matrix3d pl_rot = QuatToRot(pl_quat);
    const Vector3d pl_omg = pl_state.segment<3>(10);
    const Matrix3d pl_omg_asym = vec2asym(pl_omg);

    // qd_state = reshape(s[pl_dim_num:], (nquad, 13)): row i is vehicle i
    MatrixXd qd_state(nquad, 13);
    for (int i = 0; i < nquad; ++i) qd_state.row(i) = s.segment(13 + 13 * i, 13).transpose();
    const MatrixXd qd_pos = qd_state.leftCols(3);
    const MatrixXd qd_vel = qd_state.middleCols(3, 3);
    const MatrixXd qd_quat = qd_state.middleCols(6, 4);

    // robot_attach_vector = pl_pos + (pl_rot @ rho_vec_list).T - qd_pos  (nquad x 3)
    MatrixXd robot_attach_vector = (pl_rot * rho_vec_list).transpose() - qd_pos;
    robot_attach_vector.rowwise() += pl_pos.transpose();
    MatrixXd qd_xi = robot_attach_vector;
    for (int i = 0; i < nquad; ++i) qd_xi.row(i) /= robot_attach_vector.row(i).norm();
    MatrixXd qd_xidot = (pl_rot * (pl_omg_asym * rho_vec_list)).transpose() - qd_vel;
    qd_xidot.rowwise() += pl_vel.transpose();
    for (int i = 0; i < nquad; ++i) qd_xidot.row(i) /= cable_len_list[i];
    MatrixXd cable_omg(nquad, 3);
    for (int i = 0; i < nquad; ++i) {
      cable_omg.row(i) =
          Vector3d(qd_xi.row(i).transpose()).cross(Vector3d(qd_xidot.row(i).transpose()));
    }
    const MatrixXd attach_centrifugal_accel = pl_omg_asym * (pl_omg_asym * rho_vec_list);
    // self.attach_accel = pl_accel + [0,0,grav] + (pl_rot @ (asym(pl_ang_accel) @ rho)).T +
    //                     (pl_rot @ attach_centrifugal_accel).T
    MatrixXd attach_accel = (pl_rot * (vec2asym(pl_ang_accel) * rho_vec_list)).transpose() +
                            (pl_rot * attach_centrifugal_accel).transpose();
    attach_accel.rowwise() += (pl_accel + Vector3d(0, 0, pl_grav)).transpose();

    // payload dynamics
    Matrix3d ML = pl_mass * Matrix3d::Identity();
    Matrix3d C = Matrix3d::Zero(), D = Matrix3d::Zero(), E = Matrix3d::Zero();
    Vector3d pl_net_F = Vector3d::Zero(), pl_net_M = Vector3d::Zero();
    MatrixXd tension_vector = MatrixXd::Zero(3, nquad);
    for (int uav_idx = 0; uav_idx < nquad; ++uav_idx) {
      const Vector3d xi = qd_xi.row(uav_idx).transpose();
      const Matrix3d xixiT = xi * xi.transpose();
      const Matrix3d rho_qn_asym = P.block<3, 3>(3, 3 * uav_idx);
      const Matrix3d uav_rot = QuatToRot(qd_quat.row(uav_idx).transpose());
      const Vector3d cbl_omg = cable_omg.row(uav_idx).transpose();
      const Vector3d qd_u = uav_rot * Vector3d(0, 0, uav_F[uav_idx]);
      const Vector3d u_parallel = xixiT * qd_u;
      if (!cable_is_slack[uav_idx]) {
        const double cable_len = cable_len_list[uav_idx];
        const double mass = uav_params[uav_idx].mass;
        const Vector3d attach_qn_force =
            u_parallel - mass * cable_len * std::pow(cbl_omg.norm(), 2) * xi -
            mass * (xixiT * (pl_rot * attach_centrifugal_accel.col(uav_idx)));
        const Vector3d attach_qn_moment = rho_qn_asym * (pl_rot.transpose() * attach_qn_force);
        const double tension =
            mass * cable_len * cbl_omg.array().square().sum() -
            xi.dot(qd_u - mass * Vector3d(attach_accel.row(uav_idx).transpose()));
        tension_vector.col(uav_idx) = tension * xi;
        pl_net_F = pl_net_F + attach_qn_force;
        pl_net_M = pl_net_M + attach_qn_moment;
        const Matrix3d Ck = mass * (rho_qn_asym * (pl_rot.transpose() * xixiT));
        const Matrix3d Dk = -Ck.transpose();
        const Matrix3d Ek = Ck * (pl_rot * rho_qn_asym);
        C = C + Ck;
        D = D + Dk;
        E = E + Ek;
        ML = ML + mass * xixiT;
      }
    }
    const Matrix3d invML = ML.inverse();
    const VectorXd sdotLoad =
        rigidbody_payloadEOM_readonly(pl_state, pl_net_F, pl_net_M, invML, C, D, E);
    pl_accel = sdotLoad.segment<3>(3);
    pl_ang_accel = sdotLoad.segment<3>(10);

    VectorXd sdot(13 + 13 * nquad);
    sdot.head(13) = sdotLoad;
    for (int uav_idx = 0; uav_idx < nquad; ++uav_idx) {
      const VectorXd uav_s = qd_state.row(uav_idx).transpose();
      const double F = uav_F[uav_idx];
      const Vector3d M = uav_M.col(uav_idx);
      sdot.segment(13 + 13 * uav_idx, 13) =
          cable_is_slack[uav_idx]
              ? slack_quadEOM_readonly(uav_s, F, M, uav_idx)
              : taut_quadEOM_readonly(uav_s, F, M, tension_vector.col(uav_idx), uav_idx);
    }
    return sdot;
  }

  // rigidbody_quad_inelastic_cable_collision (collision_idx: 1 for a colliding cable)
  VectorXd rigidbody_quad_inelastic_cable_collision(VectorXd x,
                                                    const std::vector<int>& collision_idx) {
    const VectorXd xL = x.head(13);
    std::vector<int> collision_idx_int;
    for (int j = 0; j < nquad; ++j) {
      if (collision_idx[j] == 1) collision_idx_int.push_back(j);
    }
    const int ntaut_quad = static_cast<int>(collision_idx_int.size());
    const Matrix3d IL = pl_I;
    const double mL = pl_mass;
    MatrixXd rho_vec_list_c(3, ntaut_quad), rho_vec_asym_mat(3, 3 * ntaut_quad);
    for (int k = 0; k < ntaut_quad; ++k) {
      rho_vec_list_c.col(k) = rho_vec_list.col(collision_idx_int[k]);
      rho_vec_asym_mat.middleCols(3 * k, 3) = P.block<3, 3>(3, 3 * collision_idx_int[k]);
    }
    const Matrix3d pl_rot = QuatToRot(xL.segment<4>(6));
    const Vector3d pl_omg = xL.segment<3>(10);
    const Vector3d pl_vel = xL.segment<3>(3);
    MatrixXd attach_pos = pl_rot * rho_vec_list_c;
    attach_pos.colwise() += xL.segment<3>(0);
    MatrixXd robot_pos(3, ntaut_quad), robot_vel(3, ntaut_quad);
    for (int k = 0; k < ntaut_quad; ++k) {
      robot_pos.col(k) = x.segment<3>(13 * (collision_idx_int[k] + 1));
      robot_vel.col(k) = x.segment<3>(13 * (collision_idx_int[k] + 1) + 3);
    }
    MatrixXd xi = attach_pos - robot_pos;
    for (int k = 0; k < ntaut_quad; ++k) xi.col(k) /= xi.col(k).norm();
    const VectorXd robot_vel_xi_proj = xi.cwiseProduct(robot_vel).colwise().sum().transpose();
    MatrixXd xixiT_robot_vel = xi;
    for (int k = 0; k < ntaut_quad; ++k) xixiT_robot_vel.col(k) *= robot_vel_xi_proj[k];
    const MatrixXd xi_vert_robot_vel = robot_vel - xixiT_robot_vel;
    // hatrho_rotL_xi = -(pl_rot @ rho_vec_asym_mat).T @ xi, then the 3x1 diagonal blocks
    const MatrixXd hatrho_full = -(pl_rot * rho_vec_asym_mat).transpose() * xi;
    MatrixXd hatrho_rotL_xi(3, ntaut_quad);
    for (int k = 0; k < ntaut_quad; ++k) hatrho_rotL_xi.col(k) = hatrho_full.block(3 * k, k, 3, 1);
    MatrixXd G1(6, ntaut_quad);
    G1 << xi, hatrho_rotL_xi;
    Eigen::Matrix<double, 6, 6> ML = Eigen::Matrix<double, 6, 6>::Zero();
    ML.topLeftCorner<3, 3>() = mL * Matrix3d::Identity();
    ML.bottomRightCorner<3, 3>() = IL;
    VectorXd MQ_list(ntaut_quad);
    for (int k = 0; k < ntaut_quad; ++k) MQ_list[k] = uav_params[collision_idx_int[k]].mass;
    const MatrixXd MQ = MQ_list.asDiagonal();
    const MatrixXd M = ML + G1 * MQ * G1.transpose();
    const VectorXd right_element = xi * MQ * robot_vel_xi_proj;
    const VectorXd left_element = hatrho_rotL_xi * MQ * robot_vel_xi_proj;
    VectorXd b(6);
    b << mL * pl_vel + right_element, left_element + IL * pl_omg;
    const VectorXd collided_pl_vel_omg = M.colPivHouseholderQr().solve(b);  // np.linalg.lstsq
    const Vector3d collided_pl_vel = collided_pl_vel_omg.head<3>();
    const Vector3d collided_pl_omg = collided_pl_vel_omg.tail<3>();
    MatrixXd attach_vel = pl_rot * vec2asym(collided_pl_omg) * rho_vec_list_c;
    attach_vel.colwise() += collided_pl_vel;
    MatrixXd collided_robot_vel_proj = xi;
    for (int k = 0; k < ntaut_quad; ++k) {
      collided_robot_vel_proj.col(k) *= xi.col(k).dot(attach_vel.col(k));
    }
    const MatrixXd collided_robot_vel = xi_vert_robot_vel + collided_robot_vel_proj;
    x.segment<3>(3) = collided_pl_vel;
    x.segment<3>(10) = collided_pl_omg;
    for (int k = 0; k < ntaut_quad; ++k) {
      x.segment<3>(13 * (collision_idx_int[k] + 1) + 3) = collided_robot_vel.col(k);
    }
    return x;
  }
};

// RotorTM's simulator set up from a team, with the thrusts and moments of rotor speeds u.
RotorTmSimulation ToRotorTm(const CooperativeTeam& team, const std::vector<CableMode>& modes,
                            const VectorXd& u) {
  RotorTmSimulation sim;
  sim.nquad = static_cast<int>(team.vehicles.size());
  sim.pl_mass = team.payload_mass_kg;
  sim.pl_grav = team.gravity_mps2;
  sim.pl_I = team.payload_inertia_P_kgm2.asDiagonal();
  sim.pl_invI = sim.pl_I.inverse();
  sim.rho_vec_list.resize(3, sim.nquad);
  sim.cable_len_list.resize(sim.nquad);
  sim.P = MatrixXd::Zero(6, 3 * sim.nquad);
  sim.uav_F.resize(sim.nquad);
  sim.uav_M.resize(3, sim.nquad);
  for (int i = 0; i < sim.nquad; ++i) {
    const CooperativeVehicle& v = team.vehicles[i];
    sim.rho_vec_list.col(i) = v.p_PA_P_m;
    sim.cable_len_list[i] = v.cable_length_m;
    sim.P.block<3, 3>(0, 3 * i) = Matrix3d::Identity();
    sim.P.block<3, 3>(3, 3 * i) = vec2asym(v.p_PA_P_m);
    RotorTmUav uav;
    uav.mass = v.params.quad_mass_kg;
    uav.grav = v.params.gravity_mps2;
    uav.I = v.params.inertia_B_kgm2.asDiagonal();
    uav.invI = uav.I.inverse();
    sim.uav_params.push_back(uav);
    sim.cable_is_slack.push_back(modes[i] == CableMode::kSlack);
    const Eigen::Vector4d wrench = WrenchFromRotorSpeeds(v.params, u.segment<4>(4 * i));
    sim.uav_F[i] = wrench(0);
    sim.uav_M.col(i) = wrench.tail<3>();
  }
  return sim;
}

// RotorTM's derivative: the second call of its stateful EOM on the same state.
VectorXd RotorTmDerivative(const CooperativeTeam& team, const VectorXd& x, const VectorXd& u,
                           const std::vector<CableMode>& modes) {
  RotorTmSimulation sim = ToRotorTm(team, modes, u);
  sim.hybrid_cooperative_rigidbody_pl_transportationEOM(0.0, x);
  return sim.hybrid_cooperative_rigidbody_pl_transportationEOM(0.0, x);
}

// ---------------------------------------------------------------------------------------------
// Random teams and taut configurations.

// A vector with entries uniform in [-1, 1], drawn from rng (the test's one source of randomness).
Vector3d RandomVector(std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  return Vector3d(unit(*rng), unit(*rng), unit(*rng));
}

// A team of n vehicles of params' kind, each with its own cable length, mass and attachment.
CooperativeTeam RandomTeam(int n, std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  CooperativeTeam team;
  const Params p;
  team.payload_mass_kg = 0.3 + 0.2 * unit(*rng);
  team.payload_inertia_P_kgm2 = Vector3d(3e-3, 4e-3, 6e-3) + 1e-3 * RandomVector(rng);
  for (int i = 0; i < n; ++i) {
    CooperativeVehicle v;
    v.params = p;
    v.params.quad_mass_kg = p.quad_mass_kg * (1 + 0.2 * unit(*rng));
    v.params.inertia_B_kgm2 = p.inertia_B_kgm2 * (1 + 0.2 * unit(*rng));
    v.cable_length_m = 0.5 + 0.3 * unit(*rng);
    v.p_PA_P_m = 0.2 * Vector3d(unit(*rng), unit(*rng), 0.3 * unit(*rng));
    team.vehicles.push_back(v);
  }
  return team;
}

Eigen::Vector4d RandomQuaternion(std::mt19937* rng, double max_angle_rad) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const Eigen::Quaterniond q(
      Eigen::AngleAxisd(max_angle_rad * unit(*rng), RandomVector(rng).normalized()));
  return Eigen::Vector4d(q.w(), q.x(), q.y(), q.z());
}

// A state with every cable exactly at its length and not stretching (d = l, v_r = 0): the
// payload moving and rotating, each vehicle above its attachment, moving across its cable.
VectorXd RandomTautState(const CooperativeTeam& team, std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const int n = static_cast<int>(team.vehicles.size());
  VectorXd x = VectorXd::Zero(I::Size(n));
  x.segment<3>(I::kPayloadPos) = Vector3d(unit(*rng), unit(*rng), 1 + 0.5 * unit(*rng));
  x.segment<3>(I::kPayloadVel) = RandomVector(rng);
  x.segment<4>(I::kPayloadQuat) = RandomQuaternion(rng, 0.5);
  x.segment<3>(I::kPayloadRate) = 2 * RandomVector(rng);
  const Matrix3d R_WP = QuatToRot(x.segment<4>(I::kPayloadQuat));
  const Vector3d w_P = x.segment<3>(I::kPayloadRate);
  for (int i = 0; i < n; ++i) {
    const CooperativeVehicle& v = team.vehicles[i];
    const Vector3d p_A = x.segment<3>(I::kPayloadPos) + R_WP * v.p_PA_P_m;
    const Vector3d v_A = x.segment<3>(I::kPayloadVel) + R_WP * w_P.cross(v.p_PA_P_m);
    const Vector3d xi = Vector3d(0.6 * unit(*rng), 0.6 * unit(*rng), -1).normalized();
    const int b = I::Vehicle(i);
    x.segment<3>(b + I::kVehiclePos) = p_A - v.cable_length_m * xi;
    const Vector3d v_across = RandomVector(rng).cross(xi);  // perpendicular to xi
    x.segment<3>(b + I::kVehicleVel) = v_A + v_across;
    x.segment<4>(b + I::kVehicleQuat) = RandomQuaternion(rng, 0.6);
    x.segment<3>(b + I::kVehicleRate) = 3 * RandomVector(rng);
  }
  return x;
}

VectorXd RandomRotorSpeeds(int n, std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const double hover = Params().HoverMotorSpeedRadps();
  VectorXd u(4 * n);
  for (int k = 0; k < 4 * n; ++k) u[k] = hover * (1 + 0.3 * unit(*rng));
  return u;
}

double RelativeDifference(const VectorXd& a, const VectorXd& b) {
  return (a - b).norm() / b.norm();
}

// The relative difference over the cross-check's 1000 configurations per case is printed on the
// "[measured]" lines and recorded in docs/cooperative.md: the rounding of the same formulas
// evaluated in a different order. The bound is about 20x the largest measured and far below any
// physical term (a dropped or sign-flipped coupling term fails it by 1e-2 or more).
constexpr double kRotorTmTolerance = 1e-13;

class CooperativeRotorTmTest : public testing::TestWithParam<int> {};

// The model's derivative against RotorTM's on 1000 random teams of `n` vehicles drawn from
// `seed`, every cable taut or (`mixed_modes`) each taut or slack at random (the slack ones left
// where the taut layout put them); fails at the first trial beyond kRotorTmTolerance and prints
// the largest difference as `label`.
void ExpectDerivativeEqualsRotorTm(int n, unsigned seed, bool mixed_modes, const char* label) {
  std::mt19937 rng(seed);
  double worst = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const CooperativeTeam team = RandomTeam(n, &rng);
    const CooperativeModel model(team);
    const VectorXd x = RandomTautState(team, &rng);
    const VectorXd u = RandomRotorSpeeds(n, &rng);
    std::vector<CableMode> modes(n, CableMode::kTaut);
    if (mixed_modes) {
      for (int i = 0; i < n; ++i) modes[i] = rng() % 2 ? CableMode::kTaut : CableMode::kSlack;
    }
    const double diff =
        RelativeDifference(model.Derivative(x, u, modes), RotorTmDerivative(team, x, u, modes));
    worst = std::max(worst, diff);
    ASSERT_LT(diff, kRotorTmTolerance) << label << ", trial " << trial;
  }
  std::printf("[measured] N = %d %s: largest relative difference to RotorTM %.2e\n", n, label,
              worst);
}

TEST_P(CooperativeRotorTmTest, TautDerivativeEqualsRotorTmTranscription) {
  ExpectDerivativeEqualsRotorTm(GetParam(), 1000 + GetParam(), false, "taut");
}

TEST_P(CooperativeRotorTmTest, MixedModesEqualRotorTmTranscription) {
  ExpectDerivativeEqualsRotorTm(GetParam(), 2000 + GetParam(), true, "mixed modes");
}

TEST_P(CooperativeRotorTmTest, RetautCollisionEqualsRotorTmTranscription) {
  // cables at their length, stretching at random speeds; a random subset collides
  const int n = GetParam();
  std::mt19937 rng(3000 + n);
  double worst = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const CooperativeTeam team = RandomTeam(n, &rng);
    const CooperativeModel model(team);
    VectorXd x = RandomTautState(team, &rng);
    std::vector<bool> colliding(n);
    std::vector<int> collision_idx(n);
    for (int i = 0; i < n; ++i) {
      x.segment<3>(I::Vehicle(i) + I::kVehicleVel) += RandomVector(&rng);
      colliding[i] = trial % 2 == 0 || rng() % 2 == 1;
      collision_idx[i] = colliding[i] ? 1 : 0;
    }
    RotorTmSimulation sim =
        ToRotorTm(team, std::vector<CableMode>(n, CableMode::kTaut), VectorXd::Zero(4 * n));
    const VectorXd expected = sim.rigidbody_quad_inelastic_cable_collision(x, collision_idx);
    const double diff = RelativeDifference(model.RetautCollision(x, colliding), expected);
    worst = std::max(worst, diff);
    ASSERT_LT(diff, kRotorTmTolerance) << "trial " << trial;
  }
  std::printf("[measured] N = %d re-taut collision: largest relative difference to RotorTM %.2e\n",
              n, worst);
}

INSTANTIATE_TEST_SUITE_P(CooperativeTeams, CooperativeRotorTmTest, testing::Values(1, 2, 3));

// ---------------------------------------------------------------------------------------------
// N = 1 is HybridModel's taut and slack flow and its jump map.

// A single-vehicle state with the cable at length l and not stretching, or off it (d != l,
// v_r != 0) to exercise the Baumgarte terms both models share.
StateVector RandomSingleState(const Params& p, bool on_constraint, std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  SystemState s;
  s.p_WQ_W = Vector3d(unit(*rng), unit(*rng), 1.5);
  const Vector3d xi = Vector3d(0.6 * unit(*rng), 0.6 * unit(*rng), -1).normalized();
  const double d = p.cable_length_m * (on_constraint ? 1.0 : 1 + 0.05 * unit(*rng));
  s.p_WL_W = s.p_WQ_W + d * xi;
  s.v_WQ_W = RandomVector(rng);
  s.v_WL_W = s.v_WQ_W + RandomVector(rng).cross(xi) + (on_constraint ? 0.0 : 0.2) * xi;
  const Eigen::Vector4d q = RandomQuaternion(rng, 0.6);
  s.q_WB = Eigen::Quaterniond(q(0), q(1), q(2), q(3));
  s.w_B = 3 * RandomVector(rng);
  return s.ToVector();
}

// Both models evaluate the same formulas in a different order (docs/cooperative.md has the
// measured difference); the bound as for RotorTM.
TEST(CooperativeSingleVehicleTest, DerivativeEqualsHybridModel) {
  const Params p;
  const HybridModel hybrid(p);
  const CooperativeModel model(CooperativeTeam::SingleVehicle(p));
  std::mt19937 rng(7);
  double worst = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const CableMode mode = trial % 3 == 0 ? CableMode::kSlack : CableMode::kTaut;
    const StateVector x19 = RandomSingleState(p, trial % 2 == 0, &rng);
    const VectorXd u = RandomRotorSpeeds(1, &rng);
    const StateVector expected = hybrid.Derivative(x19, u, mode);
    const VectorXd x_dot =
        model.Derivative(CooperativeModel::FromSingleVehicleState(x19), u, {mode});
    StateVector got;
    got << x_dot.segment<6>(I::kPayloadPos), x_dot.segment<I::kBlockSize>(I::Vehicle(0));
    const double diff = RelativeDifference(got, expected);
    worst = std::max(worst, diff);
    ASSERT_LT(diff, kRotorTmTolerance) << "trial " << trial << " mode " << ToString(mode);
    // the payload neither turns nor is turned: its cable is at its centre
    EXPECT_EQ(x_dot.segment<7>(I::kPayloadQuat).norm(), 0.0);
  }
  std::printf("[measured] N = 1: largest relative difference to HybridModel %.2e\n", worst);
}

TEST(CooperativeSingleVehicleTest, TensionEqualsHybridModel) {
  const Params p;
  const HybridModel hybrid(p);
  const CooperativeModel model(CooperativeTeam::SingleVehicle(p));
  std::mt19937 rng(8);
  for (int trial = 0; trial < 100; ++trial) {
    const StateVector x19 = RandomSingleState(p, true, &rng);
    const VectorXd u = RandomRotorSpeeds(1, &rng);
    const double expected = hybrid.TautTensionN(x19, u);
    const double got = model.CableTensionsN(CooperativeModel::FromSingleVehicleState(x19), u,
                                            {CableMode::kTaut})(0);
    EXPECT_NEAR(got, expected, 1e-12 * std::abs(expected) + 1e-12);
  }
}

TEST(CooperativeSingleVehicleTest, RetautCollisionEqualsHybridJumpMap) {
  // on the constraint HybridModel's jump map moves no position: only the velocity jump remains
  const Params p;
  const HybridModel hybrid(p);
  const CooperativeModel model(CooperativeTeam::SingleVehicle(p));
  std::mt19937 rng(9);
  for (int trial = 0; trial < 100; ++trial) {
    StateVector x19 = RandomSingleState(p, true, &rng);
    const Vector3d xi =
        (x19.segment<3>(StateIndex::kPayloadPos) - x19.segment<3>(StateIndex::kQuadPos))
            .normalized();
    x19.segment<3>(StateIndex::kPayloadVel) += (0.1 + trial * 0.01) * xi;  // stretching
    const VectorXd x = CooperativeModel::FromSingleVehicleState(x19);
    ASSERT_TRUE(model.RetautingCables(x)[0]);
    const StateVector expected = hybrid.ProjectToTaut(x19);
    const VectorXd y = model.RetautCollision(x, {true});
    StateVector got;
    got << y.segment<6>(I::kPayloadPos), y.segment<I::kBlockSize>(I::Vehicle(0));
    EXPECT_LT(RelativeDifference(got, expected), kRotorTmTolerance) << "trial " << trial;
  }
}

// ---------------------------------------------------------------------------------------------
// Physical checks that hold whatever the source says.

TEST(CooperativeModelTest, TautFlowKeepsEveryCableLengthConstant) {
  // d(d_i)/dt = 0 and d^2(d_i)/dt^2 = 0 on the constraint: the vehicles' and the attachments'
  // accelerations agree along each cable up to the centripetal term. Checked by a short RK4
  // rollout: the cables' lengths drift by O(dt^4) only.
  std::mt19937 rng(11);
  for (int n = 2; n <= 3; ++n) {
    const CooperativeTeam team = RandomTeam(n, &rng);
    const CooperativeModel model(team);
    VectorXd x = RandomTautState(team, &rng);
    const VectorXd u = RandomRotorSpeeds(n, &rng);
    const std::vector<CableMode> modes(n, CableMode::kTaut);
    for (int k = 0; k < 100; ++k) x = model.Step(x, u, modes, 1e-3);
    const Matrix3d R_WP = QuatToRot(x.segment<4>(I::kPayloadQuat));
    double worst_m = 0;
    for (int i = 0; i < n; ++i) {
      const Vector3d p_A = x.segment<3>(I::kPayloadPos) + R_WP * team.vehicles[i].p_PA_P_m;
      const double d = (p_A - x.segment<3>(I::Vehicle(i) + I::kVehiclePos)).norm();
      worst_m = std::max(worst_m, std::abs(d - team.vehicles[i].cable_length_m));
      // RK4's O(dt^4) drift, closed by the Baumgarte terms: printed below, bound far above it
      // and far below a missing centripetal term's (centimetres within 0.1 s)
      EXPECT_NEAR(d, team.vehicles[i].cable_length_m, 1e-10) << "N " << n << " cable " << i;
    }
    std::printf("[measured] N = %d: largest cable length drift over 0.1 s of RK4 %.2e m\n", n,
                worst_m);
  }
}

TEST(CooperativeModelTest, HangingTeamUnderHoverThrustStaysAtRest) {
  // three vehicles straight above a point payload: each carries a third of its weight
  const Params p;
  CooperativeTeam team;
  team.payload_mass_kg = 0.3;
  team.gravity_mps2 = p.gravity_mps2;
  for (int i = 0; i < 3; ++i) {
    CooperativeVehicle v;
    v.params = p;
    v.cable_length_m = 0.5 + 0.1 * i;
    team.vehicles.push_back(v);
  }
  const CooperativeModel model(team);
  const VectorXd x = model.HangingState(Vector3d(0, 0, 1));
  const double thrust_N = (p.quad_mass_kg + team.payload_mass_kg / 3) * p.gravity_mps2;
  const double w = std::sqrt(thrust_N / (4 * p.k_f_N_per_radps2));
  const VectorXd u = VectorXd::Constant(12, w);
  const std::vector<CableMode> modes(3, CableMode::kTaut);
  EXPECT_LT(model.Derivative(x, u, modes).norm(), 1e-12);
  const VectorXd tensions = model.CableTensionsN(x, u, modes);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(tensions(i), team.payload_mass_kg * p.gravity_mps2 / 3, 1e-12);
  }
}

TEST(CooperativeModelTest, RetautCollisionKeepsMomentumAndStopsTheStretch) {
  std::mt19937 rng(13);
  for (int n = 1; n <= 3; ++n) {
    const CooperativeTeam team = RandomTeam(n, &rng);
    const CooperativeModel model(team);
    VectorXd x = RandomTautState(team, &rng);
    for (int i = 0; i < n; ++i) {
      x.segment<3>(I::Vehicle(i) + I::kVehicleVel) += RandomVector(&rng);
    }
    const std::vector<bool> colliding(n, true);
    const VectorXd y = model.RetautCollision(x, colliding);
    // linear momentum: the impulses are internal
    auto momentum = [&](const VectorXd& s) {
      Vector3d m = team.payload_mass_kg * s.segment<3>(I::kPayloadVel);
      for (int i = 0; i < n; ++i) {
        m += team.vehicles[i].params.quad_mass_kg * s.segment<3>(I::Vehicle(i) + I::kVehicleVel);
      }
      return m;
    };
    EXPECT_LT((momentum(y) - momentum(x)).norm(), 1e-12 * momentum(x).norm() + 1e-12);
    // no cable stretches after it
    for (int i = 0; i < n; ++i) {
      EXPECT_FALSE(model.RetautingCables(y, 1e-3, 1e-9)[i]) << "N " << n << " cable " << i;
    }
  }
}

TEST(CooperativeModelTest, RejectsAnEmptyTeamAndWrongSizes) {
  EXPECT_THROW(CooperativeModel(CooperativeTeam{}), std::invalid_argument);
  const CooperativeModel model(CooperativeTeam::SingleVehicle(Params()));
  EXPECT_THROW(model.Derivative(VectorXd::Zero(26), VectorXd::Zero(4), {}), std::invalid_argument);
}

}  // namespace
}  // namespace hpa
