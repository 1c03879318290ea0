#include "exact_derivatives.h"

#include "hpa/models/rotor_model.h"

namespace hpa {
namespace {

using I = StateIndex;

// The thrust vector f R e3 in world and its Jacobians in q (3 x 4) and u (3 x 4).
struct ThrustVectorJacobian {
  Eigen::Vector3d f_W_N;              // f R e3, world
  Eigen::Matrix<double, 3, 4> f_q;    // d f / d q
  Eigen::Matrix<double, 3, kNu> f_u;  // d f / d u
};

// The thrust vector f R e3 and its Jacobians from the rotor part at the state's attitude.
ThrustVectorJacobian ThrustVector(const RotorJacobian& rotor, const StateVector& x) {
  const double qw = x(I::kQuat), qx = x(I::kQuat + 1), qy = x(I::kQuat + 2), qz = x(I::kQuat + 3);
  // body z in world (third column of R(q)) and its derivative in (w, x, y, z)
  const Eigen::Vector3d z_B_W(2.0 * (qx * qz + qw * qy), 2.0 * (qy * qz - qw * qx),
                              1.0 - 2.0 * (qx * qx + qy * qy));
  Eigen::Matrix<double, 3, 4> z_q;
  z_q << 2.0 * qy, 2.0 * qz, 2.0 * qw, 2.0 * qx,  //
      -2.0 * qx, -2.0 * qw, 2.0 * qz, 2.0 * qy,   //
      0.0, -4.0 * qx, -4.0 * qy, 0.0;
  ThrustVectorJacobian t;
  t.f_W_N = rotor.thrust_N * z_B_W;
  t.f_q = rotor.thrust_N * z_q;
  t.f_u = z_B_W * rotor.thrust_u;
  return t;
}

// The cable-force blocks of the taut flow (a_L = -T xi / m_L - g e3, a_Q = (f + T xi) / m - g e3):
// d (T xi) / d (r, v, q, u) with T the tension of HybridModel's taut flow and xi = r / |r|.
void TautAccelerationJacobian(const Params& p, const StateVector& x, const ThrustVectorJacobian& f,
                              FlowJacobian* j) {
  const double m = p.quad_mass_kg, m_L = p.payload_mass_kg;
  const double mu_kg = m * m_L / (m + m_L);
  const double k_p = HybridModel::kBaumgarteStiffness, k_d = HybridModel::kBaumgarteDamping;
  const Eigen::Vector3d r_W = x.segment<3>(I::kPayloadPos) - x.segment<3>(I::kQuadPos);
  const Eigen::Vector3d v_W = x.segment<3>(I::kPayloadVel) - x.segment<3>(I::kQuadVel);
  const double d_m = r_W.norm();
  const Eigen::Vector3d xi_W = r_W / d_m;
  const double v_r_mps = v_W.dot(xi_W);
  const double v_perp_sq_m2ps2 = v_W.squaredNorm() - v_r_mps * v_r_mps;
  const double tension_N = mu_kg * (v_perp_sq_m2ps2 / d_m - xi_W.dot(f.f_W_N) / m + k_d * v_r_mps +
                                    k_p * (d_m - p.cable_length_m));
  // d xi / d r = (I - xi xi^T) / d, symmetric
  const Eigen::Matrix3d xi_r = (Eigen::Matrix3d::Identity() - xi_W * xi_W.transpose()) / d_m;
  const Eigen::Vector3d v_r_r = xi_r * v_W;  // d v_r / d r
  // gradients of the tension in r, v (= v_L - v_Q), q and u
  const Eigen::Vector3d t_r =
      mu_kg * (-2.0 * v_r_mps / d_m * v_r_r - v_perp_sq_m2ps2 / (d_m * d_m) * xi_W -
               xi_r * f.f_W_N / m + k_d * v_r_r + k_p * xi_W);
  const Eigen::Vector3d t_v = mu_kg * (2.0 * (v_W - v_r_mps * xi_W) / d_m + k_d * xi_W);
  const Eigen::Vector4d t_q = -mu_kg / m * f.f_q.transpose() * xi_W;
  const Eigen::Vector4d t_u = -mu_kg / m * f.f_u.transpose() * xi_W;
  // d (T xi): xi dT + T d xi
  j->cable_r = xi_W * t_r.transpose() + tension_N * xi_r;
  j->cable_v = xi_W * t_v.transpose();
  j->cable_q = xi_W * t_q.transpose();
  j->cable_u = xi_W * t_u.transpose();
}

// Attitude kinematics q_dot = 1/2 q (x) [0, w] and Euler's equation J w_dot = M - w x J w.
void AttitudeJacobian(const Params& p, const StateVector& x, FlowJacobian* j) {
  const double qw = x(I::kQuat), qx = x(I::kQuat + 1), qy = x(I::kQuat + 2), qz = x(I::kQuat + 3);
  const Eigen::Vector3d w = x.segment<3>(I::kBodyRate);
  j->qdot_q << 0.0, -w(0), -w(1), -w(2),  //
      w(0), 0.0, w(2), -w(1),             //
      w(1), -w(2), 0.0, w(0),             //
      w(2), w(1), -w(0), 0.0;
  j->qdot_q *= 0.5;
  j->qdot_w << -qx, -qy, -qz,  //
      qw, -qz, qy,             //
      qz, qw, -qx,             //
      -qy, qx, qw;
  j->qdot_w *= 0.5;
  const Eigen::Vector3d& in = p.inertia_B_kgm2;
  // d (w x J w) / dw
  Eigen::Matrix3d gyro_w;
  gyro_w << 0.0, (in(2) - in(1)) * w(2), (in(2) - in(1)) * w(1),  //
      (in(0) - in(2)) * w(2), 0.0, (in(0) - in(2)) * w(0),        //
      (in(1) - in(0)) * w(1), (in(1) - in(0)) * w(0), 0.0;
  for (int i = 0; i < 3; ++i) j->wdot_w.row(i) = -gyro_w.row(i) / in(i);
}

}  // namespace

RotorJacobian EvaluateRotorJacobian(const Params& params, const Eigen::Matrix4d& allocation,
                                    const InputVector& u) {
  // wrench = allocation * k_f u.^2: d wrench / du = allocation * diag(2 k_f u)
  const Eigen::Vector4d f_rotor_N = params.k_f_N_per_radps2 * u.array().square().matrix();
  const Eigen::Matrix4d wrench_u =
      allocation * (2.0 * params.k_f_N_per_radps2 * u).asDiagonal().toDenseMatrix();
  RotorJacobian rotor;
  rotor.thrust_N = allocation.row(0).dot(f_rotor_N);
  rotor.thrust_u = wrench_u.row(0);
  for (int i = 0; i < 3; ++i) rotor.wdot_u.row(i) = wrench_u.row(1 + i) / params.inertia_B_kgm2(i);
  return rotor;
}

void EvaluateFlowJacobian(const Params& params, const RotorJacobian& rotor, const StateVector& x,
                          CableMode mode, FlowJacobian* jacobian) {
  const ThrustVectorJacobian f = ThrustVector(rotor, x);
  jacobian->taut = mode == CableMode::kTaut;
  jacobian->inv_payload_mass_per_kg = 1.0 / params.payload_mass_kg;
  jacobian->inv_quad_mass_per_kg = 1.0 / params.quad_mass_kg;
  jacobian->thrust_q = f.f_q;
  jacobian->thrust_u = f.f_u;
  jacobian->wdot_u = rotor.wdot_u;
  // slack: payload in free fall, no cable force
  if (jacobian->taut) TautAccelerationJacobian(params, x, f, jacobian);
  AttitudeJacobian(params, x, jacobian);
}

void EvaluateFlowJacobian(const Params& params, const Eigen::Matrix4d& allocation,
                          const StateVector& x, const InputVector& u, CableMode mode,
                          FlowJacobian* jacobian) {
  EvaluateFlowJacobian(params, EvaluateRotorJacobian(params, allocation, u), x, mode, jacobian);
}

void DenseFlowJacobian(const FlowJacobian& jacobian, StateMatrix* a, InputMatrix* b) {
  StepSensitivity k;
  FlowJacobianMatrix(jacobian, &k);
  *a = k.leftCols<kNx>();
  *b = k.rightCols<kNu>();
}

void FlowJacobianMatrix(const FlowJacobian& j, StepSensitivity* k) {
  // ApplyFlowJacobian of the identity: each of its products has a single nonzero term, so the
  // blocks are placed directly, with the same operations on them (negation, the force sum, the
  // mass scaling) as there
  k->setZero();
  // positions: p_dot = v
  k->block<3, 3>(I::kPayloadPos, I::kPayloadVel).setIdentity();
  k->block<3, 3>(I::kQuadPos, I::kQuadVel).setIdentity();
  // accelerations from the thrust vector f and the cable force T xi
  Eigen::Matrix<double, 3, kNxu> force = Eigen::Matrix<double, 3, kNxu>::Zero();
  force.middleCols<4>(I::kQuat) = j.thrust_q;
  force.rightCols<kNu>() = j.thrust_u;
  if (j.taut) {
    Eigen::Matrix<double, 3, kNxu> cable = Eigen::Matrix<double, 3, kNxu>::Zero();
    cable.middleCols<3>(I::kPayloadPos) = j.cable_r;
    cable.middleCols<3>(I::kPayloadVel) = j.cable_v;
    cable.middleCols<3>(I::kQuadPos) = -j.cable_r;
    cable.middleCols<3>(I::kQuadVel) = -j.cable_v;
    cable.middleCols<4>(I::kQuat) = j.cable_q;
    cable.rightCols<kNu>() = j.cable_u;
    k->middleRows<3>(I::kPayloadVel) = -j.inv_payload_mass_per_kg * cable;
    force += cable;
  }
  k->middleRows<3>(I::kQuadVel) = j.inv_quad_mass_per_kg * force;
  // attitude (q, w) and rate (w, u) rows
  k->block<4, 4>(I::kQuat, I::kQuat) = j.qdot_q;
  k->block<4, 3>(I::kQuat, I::kBodyRate) = j.qdot_w;
  k->block<3, 3>(I::kBodyRate, I::kBodyRate) = j.wdot_w;
  k->block<3, kNu>(I::kBodyRate, kNx) = j.wdot_u;
}

void ApplyFlowJacobian(const FlowJacobian& j, const StepSensitivity& s, StepSensitivity* k) {
  // columns the attitude rows of s can be nonzero in (q, w, u), and the rate rows (w, u)
  constexpr int kQuatCols = kNxu - I::kQuat, kRateCols = kNxu - I::kBodyRate;
  const auto s_q = s.block<4, kQuatCols>(I::kQuat, I::kQuat);
  const auto s_w = s.block<3, kRateCols>(I::kBodyRate, I::kBodyRate);
  // positions: p_dot = v
  k->middleRows<3>(I::kPayloadPos) = s.middleRows<3>(I::kPayloadVel);
  k->middleRows<3>(I::kQuadPos) = s.middleRows<3>(I::kQuadVel);
  // accelerations from the thrust vector f and the cable force T xi
  Eigen::Matrix<double, 3, kNxu> force = Eigen::Matrix<double, 3, kNxu>::Zero();
  force.rightCols<kQuatCols>().noalias() = j.thrust_q.lazyProduct(s_q);
  force.rightCols<kNu>() += j.thrust_u;
  if (j.taut) {
    const Eigen::Matrix<double, 3, kNxu> s_r =
        s.middleRows<3>(I::kPayloadPos) - s.middleRows<3>(I::kQuadPos);
    const Eigen::Matrix<double, 3, kNxu> s_v =
        s.middleRows<3>(I::kPayloadVel) - s.middleRows<3>(I::kQuadVel);
    Eigen::Matrix<double, 3, kNxu> cable;
    cable.noalias() = j.cable_r.lazyProduct(s_r);
    cable.noalias() += j.cable_v.lazyProduct(s_v);
    cable.rightCols<kQuatCols>().noalias() += j.cable_q.lazyProduct(s_q);
    cable.rightCols<kNu>() += j.cable_u;
    k->middleRows<3>(I::kPayloadVel) = -j.inv_payload_mass_per_kg * cable;
    force += cable;
  } else {
    k->middleRows<3>(I::kPayloadVel).setZero();
  }
  k->middleRows<3>(I::kQuadVel) = j.inv_quad_mass_per_kg * force;
  // attitude (q, w) and rate (w) rows keep the pattern
  k->block<4, I::kQuat>(I::kQuat, 0).setZero();
  k->block<4, kQuatCols>(I::kQuat, I::kQuat).noalias() = j.qdot_q.lazyProduct(s_q);
  k->block<4, kRateCols>(I::kQuat, I::kBodyRate).noalias() += j.qdot_w.lazyProduct(s_w);
  k->block<3, I::kBodyRate>(I::kBodyRate, 0).setZero();
  k->block<3, kRateCols>(I::kBodyRate, I::kBodyRate).noalias() = j.wdot_w.lazyProduct(s_w);
  k->block<3, kNu>(I::kBodyRate, kNx) += j.wdot_u;
}

namespace {

// s = I + h k over the rigid body's pattern (the attitude rows' position and velocity columns
// and the rate rows' attitude columns are left as they are: zero in s and k). k may be an
// expression (the RK4 sum), evaluated on those blocks only.
template <typename Sensitivity>
void SensitivityOnPattern(double h, const Eigen::MatrixBase<Sensitivity>& k, StepSensitivity* s) {
  constexpr int kQuatCols = kNxu - I::kQuat, kRateCols = kNxu - I::kBodyRate;
  s->topRows<I::kQuat>().noalias() = h * k.template topRows<I::kQuat>();
  s->block<4, kQuatCols>(I::kQuat, I::kQuat).noalias() =
      h * k.template block<4, kQuatCols>(I::kQuat, I::kQuat);
  s->bottomRightCorner<kNx - I::kBodyRate, kRateCols>().noalias() =
      h * k.template bottomRightCorner<kNx - I::kBodyRate, kRateCols>();
  s->leftCols<kNx>().diagonal().array() += 1.0;
}

}  // namespace

void ExactStepJacobians(const HybridModel& model, const StateVector& x, const InputVector& u,
                        CableMode mode, double dt_s, StateVector* x_next, StateMatrix* a,
                        InputMatrix* b) {
  const Params& p = model.params();
  // u is held over the step: the rotor map's part of the flow Jacobian is the same at every stage
  const RotorJacobian rotor = EvaluateRotorJacobian(p, AllocationMatrix(p), u);
  // the stages as HybridModel's RK4 forms them, with their sensitivities s_i = d x_i / d(x, u);
  // every sensitivity has the rigid body's pattern, whose zeros are set once here
  FlowJacobian j;
  // 16-byte aligned: Eigen chooses between its vectorised and scalar paths for a block by where
  // the block starts, and the two sum some products in different orders; fixed alignment keeps
  // the values independent of where the compiler places these (19 x 23 is not a multiple of 16
  // bytes, so Eigen itself does not align them)
  alignas(16) StepSensitivity k1, k2, k3, k4;
  alignas(16) StepSensitivity s = StepSensitivity::Zero();
  const StateVector f1 = model.Derivative(x, u, mode);
  EvaluateFlowJacobian(p, rotor, x, mode, &j);
  FlowJacobianMatrix(j, &k1);  // s_1 = I
  const StateVector x2 = (x + (0.5 * dt_s) * f1).eval();
  const StateVector f2 = model.Derivative(x2, u, mode);
  EvaluateFlowJacobian(p, rotor, x2, mode, &j);
  SensitivityOnPattern(0.5 * dt_s, k1, &s);
  ApplyFlowJacobian(j, s, &k2);
  const StateVector x3 = (x + (0.5 * dt_s) * f2).eval();
  const StateVector f3 = model.Derivative(x3, u, mode);
  EvaluateFlowJacobian(p, rotor, x3, mode, &j);
  SensitivityOnPattern(0.5 * dt_s, k2, &s);
  ApplyFlowJacobian(j, s, &k3);
  const StateVector x4 = (x + dt_s * f3).eval();
  const StateVector f4 = model.Derivative(x4, u, mode);
  EvaluateFlowJacobian(p, rotor, x4, mode, &j);
  SensitivityOnPattern(dt_s, k3, &s);
  ApplyFlowJacobian(j, s, &k4);
  StateVector y = x + (dt_s / 6.0) * (f1 + 2.0 * f2 + 2.0 * f3 + f4);
  SensitivityOnPattern(dt_s / 6.0, k1 + 2.0 * k2 + 2.0 * k3 + k4, &s);
  // renormalisation q / |q|: d (q / |q|) = (I - q q^T / |q|^2) / |q| dq
  const double q_norm = y.segment<4>(I::kQuat).norm();
  y.segment<4>(I::kQuat) /= q_norm;
  const Eigen::Vector4d q_unit = y.segment<4>(I::kQuat);
  const Eigen::Matrix4d normalise =
      (Eigen::Matrix4d::Identity() - q_unit * q_unit.transpose()) / q_norm;
  // (the attitude rows are zero in the position and velocity columns)
  constexpr int kQuatCols = kNxu - I::kQuat;
  const Eigen::Matrix<double, 4, kQuatCols> s_q =
      normalise.lazyProduct(s.block<4, kQuatCols>(I::kQuat, I::kQuat));
  s.block<4, kQuatCols>(I::kQuat, I::kQuat) = s_q;
  *x_next = y;
  *a = s.leftCols<kNx>();
  *b = s.rightCols<kNu>();
}

StateVector ExactJumpJacobian(const HybridModel& model, const StateVector& x,
                              StateMatrix* jacobian) {
  const Params& p = model.params();
  const double m = p.quad_mass_kg, m_L = p.payload_mass_kg, l = p.cable_length_m;
  const double mass_kg = m + m_L;
  const Eigen::Vector3d r_W = x.segment<3>(I::kPayloadPos) - x.segment<3>(I::kQuadPos);
  const double d_m = r_W.norm();
  const bool degenerate = !(d_m > 1e-6);
  const Eigen::Vector3d xi_W = degenerate ? Eigen::Vector3d(0, 0, -1) : Eigen::Vector3d(r_W / d_m);
  // d xi / d r (zero where the map takes a fixed direction)
  const Eigen::Matrix3d xi_r =
      degenerate ? Eigen::Matrix3d::Zero()
                 : Eigen::Matrix3d((Eigen::Matrix3d::Identity() - xi_W * xi_W.transpose()) / d_m);
  const double d_taut_m = std::min(std::max(d_m, l - p.slack_epsilon_m), l);
  const Eigen::Matrix3d id = Eigen::Matrix3d::Identity();
  jacobian->setIdentity();
  if (d_taut_m != d_m || degenerate) {
    // y_Q = c - m_L / M d_taut xi, y_L = c + m / M d_taut xi, c the centre of mass; d_taut fixed
    const Eigen::Matrix3d lever = d_taut_m * xi_r;
    jacobian->block<3, 3>(I::kQuadPos, I::kQuadPos) = (m / mass_kg) * id + (m_L / mass_kg) * lever;
    jacobian->block<3, 3>(I::kQuadPos, I::kPayloadPos) = (m_L / mass_kg) * (id - lever);
    jacobian->block<3, 3>(I::kPayloadPos, I::kQuadPos) = (m / mass_kg) * (id - lever);
    jacobian->block<3, 3>(I::kPayloadPos, I::kPayloadPos) =
        (m_L / mass_kg) * id + (m / mass_kg) * lever;
  }
  const Eigen::Vector3d v_W = x.segment<3>(I::kPayloadVel) - x.segment<3>(I::kQuadVel);
  const double v_rel_mps = v_W.dot(xi_W);
  if (v_rel_mps > 0.0) {
    // y_vQ = v_Q + m_L / M (v . xi) xi, y_vL = v_L - m / M (v . xi) xi
    const Eigen::Matrix3d xx = xi_W * xi_W.transpose();
    const Eigen::Matrix3d sxi_r = (xi_W * v_W.transpose() + v_rel_mps * id) * xi_r;
    for (int row : {I::kQuadVel, I::kPayloadVel}) {
      const double s = row == I::kQuadVel ? m_L / mass_kg : -m / mass_kg;
      jacobian->block<3, 3>(row, I::kPayloadVel) += s * xx;
      jacobian->block<3, 3>(row, I::kQuadVel) -= s * xx;
      jacobian->block<3, 3>(row, I::kPayloadPos) = s * sxi_r;
      jacobian->block<3, 3>(row, I::kQuadPos) = -s * sxi_r;
    }
  }
  return model.ProjectToTaut(x);
}

}  // namespace hpa
