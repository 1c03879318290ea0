#pragma once
// An independent, line-by-line transcription of RotorTM's cooperative cable-suspended payload
// simulator (arplaboratory/RotorTM, rotor_tm_sim/src/rotor_tm_sim/simulation_base.py:
// hybrid_cooperative_rigidbody_pl_transportationEOM, rigidbody_payloadEOM_readonly,
// taut_quadEOM_readonly, slack_quadEOM_readonly, rigidbody_quad_inelastic_cable_collision;
// rotor_tm_utils/utilslib.py: QuatToRot, quat_dot, vec2asym; rotor_tm_utils/read_params.py: P),
// and its setup from a CooperativeTeam (ToRotorTm): the reference cooperative_rotor_tm_test.cc
// checks hpa::CooperativeModel against.

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "hpa/models/cooperative_model.h"
#include "hpa/models/rotor_model.h"

namespace hpa::rotor_tm {

using Eigen::Matrix3d;
using Eigen::MatrixXd;
using Eigen::Vector3d;
using Eigen::VectorXd;

// RotorTM, transcribed as its Python reads (numpy arrays as Eigen, names kept). Its simulator
// object keeps the payload's last accelerations (self.pl_accel, self.pl_ang_accel) and uses them
// in the tension; the payload's own accelerations do not depend on them, so a second call on the
// same state is RotorTM's consistent derivative.

// utilslib.vec2asym
inline Matrix3d vec2asym(const Vector3d& vec) {
  Matrix3d mat;
  mat << 0, -vec[2], vec[1], vec[2], 0, -vec[0], -vec[1], vec[0], 0;
  return mat;
}

// utilslib.QuatToRot
inline Matrix3d QuatToRot(Eigen::Vector4d q) {
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
inline Eigen::Vector4d quat_dot(const Eigen::Vector4d& quat, const Vector3d& omg) {
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

  // the taut cables' sums of hybrid_cooperative_rigidbody_pl_transportationEOM's payload
  // dynamics (its loop over the vehicles): ML, C, D, E, the net force and moment on the payload
  // and each cable's tension vector (a column per vehicle, zero for a slack cable)
  struct TautCableSums {
    Matrix3d ML, C, D, E;
    Vector3d pl_net_F, pl_net_M;
    MatrixXd tension_vector;  // 3 x nquad
  };
  TautCableSums taut_cable_sums(const Matrix3d& pl_rot, const MatrixXd& qd_quat,
                                const MatrixXd& qd_xi, const MatrixXd& cable_omg,
                                const MatrixXd& attach_centrifugal_accel,
                                const MatrixXd& attach_accel) {
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
    return {ML, C, D, E, pl_net_F, pl_net_M, tension_vector};
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
    const TautCableSums sums =
        taut_cable_sums(pl_rot, qd_quat, qd_xi, cable_omg, attach_centrifugal_accel, attach_accel);
    const Matrix3d& ML = sums.ML;
    const Matrix3d &C = sums.C, &D = sums.D, &E = sums.E;
    const Vector3d &pl_net_F = sums.pl_net_F, &pl_net_M = sums.pl_net_M;
    const MatrixXd& tension_vector = sums.tension_vector;
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
inline RotorTmSimulation ToRotorTm(const CooperativeTeam& team, const std::vector<CableMode>& modes,
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
inline VectorXd RotorTmDerivative(const CooperativeTeam& team, const VectorXd& x, const VectorXd& u,
                                  const std::vector<CableMode>& modes) {
  RotorTmSimulation sim = ToRotorTm(team, modes, u);
  sim.hybrid_cooperative_rigidbody_pl_transportationEOM(0.0, x);
  return sim.hybrid_cooperative_rigidbody_pl_transportationEOM(0.0, x);
}

}  // namespace hpa::rotor_tm
