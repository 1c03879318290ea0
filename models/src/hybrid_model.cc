#include "hpa/models/hybrid_model.h"

#include <algorithm>
#include <unsupported/Eigen/AutoDiff>

#include "hpa/models/rotor_model.h"

namespace hpa {
namespace {

constexpr int kNxu = kNx + kNu;
using AdScalar = Eigen::AutoDiffScalar<Eigen::Matrix<double, kNxu, 1>>;

template <typename T>
using Vec3 = Eigen::Matrix<T, 3, 1>;

// Continuous dynamics for any scalar type (double or forward-mode AD).
template <typename T>
Eigen::Matrix<T, kNx, 1> Flow(const Params& p, const Eigen::Matrix4d& allocation,
                              const Eigen::Matrix<T, kNx, 1>& x, const Eigen::Matrix<T, kNu, 1>& u,
                              CableMode mode) {
  using I = StateIndex;
  const Vec3<T> p_L = x.template segment<3>(I::kPayloadPos);
  const Vec3<T> v_L = x.template segment<3>(I::kPayloadVel);
  const Vec3<T> p_Q = x.template segment<3>(I::kQuadPos);
  const Vec3<T> v_Q = x.template segment<3>(I::kQuadVel);
  const T qw = x(I::kQuat), qx = x(I::kQuat + 1), qy = x(I::kQuat + 2), qz = x(I::kQuat + 3);
  const Vec3<T> w = x.template segment<3>(I::kBodyRate);

  // rotor thrusts and the body wrench
  Eigen::Matrix<T, 4, 1> f_rotor;
  for (int i = 0; i < 4; ++i) f_rotor(i) = T(p.k_f_N_per_radps2) * u(i) * u(i);
  const Eigen::Matrix<T, 4, 1> wrench = allocation.cast<T>() * f_rotor;
  const T thrust = wrench(0);

  // body z axis in world: third column of R(q)
  const Vec3<T> z_B_W(T(2) * (qx * qz + qw * qy), T(2) * (qy * qz - qw * qx),
                      T(1) - T(2) * (qx * qx + qy * qy));
  const Vec3<T> f_W = thrust * z_B_W;
  const Vec3<T> g_W(T(0), T(0), T(-p.gravity_mps2));

  const double m = p.quad_mass_kg;
  const double m_L = p.payload_mass_kg;
  Vec3<T> a_L, a_Q;
  if (mode == CableMode::kTaut) {
    const Vec3<T> r = p_L - p_Q;
    const T d = r.norm();
    const Vec3<T> xi = r / d;
    const Vec3<T> v_rel = v_L - v_Q;
    const T v_r = v_rel.dot(xi);
    const T v_perp_sq = v_rel.squaredNorm() - v_r * v_r;
    const double mu = m * m_L / (m + m_L);
    const T tension = mu * (v_perp_sq / d - xi.dot(f_W) / m + HybridModel::kBaumgarteDamping * v_r +
                            HybridModel::kBaumgarteStiffness * (d - p.cable_length_m));
    a_L = -tension / m_L * xi + g_W;
    a_Q = (f_W + tension * xi) / m + g_W;
  } else {
    a_L = g_W;
    a_Q = f_W / m + g_W;
  }

  // attitude kinematics q_dot = 1/2 q (x) [0, w] and Euler's equation
  Eigen::Matrix<T, 4, 1> q_dot;
  q_dot << T(-0.5) * (qx * w(0) + qy * w(1) + qz * w(2)),
      T(0.5) * (qw * w(0) + qy * w(2) - qz * w(1)), T(0.5) * (qw * w(1) + qz * w(0) - qx * w(2)),
      T(0.5) * (qw * w(2) + qx * w(1) - qy * w(0));
  const Vec3<T> j = p.inertia_B_kgm2.cast<T>();
  const Vec3<T> jw = j.cwiseProduct(w);
  const Vec3<T> moment = wrench.template tail<3>();
  const Vec3<T> w_dot = (moment - w.cross(jw)).cwiseQuotient(j);

  Eigen::Matrix<T, kNx, 1> x_dot;
  x_dot << v_L, a_L, v_Q, a_Q, q_dot, w_dot;
  return x_dot;
}

// RK4 step with the quaternion renormalised, for any scalar type.
template <typename T>
Eigen::Matrix<T, kNx, 1> Rk4(const Params& p, const Eigen::Matrix4d& allocation,
                             const Eigen::Matrix<T, kNx, 1>& x, const Eigen::Matrix<T, kNu, 1>& u,
                             CableMode mode, double dt) {
  const auto k1 = Flow<T>(p, allocation, x, u, mode);
  const auto k2 = Flow<T>(p, allocation, (x + T(0.5 * dt) * k1).eval(), u, mode);
  const auto k3 = Flow<T>(p, allocation, (x + T(0.5 * dt) * k2).eval(), u, mode);
  const auto k4 = Flow<T>(p, allocation, (x + T(dt) * k3).eval(), u, mode);
  Eigen::Matrix<T, kNx, 1> x_next = x + T(dt / 6.0) * (k1 + T(2) * k2 + T(2) * k3 + k4);
  const T q_norm = x_next.template segment<4>(StateIndex::kQuat).norm();
  x_next.template segment<4>(StateIndex::kQuat) /= q_norm;
  return x_next;
}

// Seeds AD variables: derivative i of x_u(i) is 1.
void Seed(const StateVector& x, const InputVector& u, Eigen::Matrix<AdScalar, kNx, 1>* x_ad,
          Eigen::Matrix<AdScalar, kNu, 1>* u_ad) {
  for (int i = 0; i < kNx; ++i) {
    (*x_ad)(i) = AdScalar(x(i), kNxu, i);
  }
  for (int i = 0; i < kNu; ++i) {
    (*u_ad)(i) = AdScalar(u(i), kNxu, kNx + i);
  }
}

// Splits AD results into value and Jacobians.
void Unpack(const Eigen::Matrix<AdScalar, kNx, 1>& y, StateVector* value, StateMatrix* a,
            InputMatrix* b) {
  for (int i = 0; i < kNx; ++i) {
    if (value != nullptr) (*value)(i) = y(i).value();
    const auto& d = y(i).derivatives();
    if (a != nullptr) a->row(i) = d.head<kNx>().transpose();
    if (b != nullptr) b->row(i) = d.tail<kNu>().transpose();
  }
}

// The jump map a cable can give (HybridModel::ProjectToTaut), for any scalar type.
template <typename T>
Eigen::Matrix<T, kNx, 1> JumpMap(const Params& p, const Eigen::Matrix<T, kNx, 1>& x) {
  using I = StateIndex;
  const double m = p.quad_mass_kg, m_L = p.payload_mass_kg, l = p.cable_length_m;
  const Vec3<T> p_L = x.template segment<3>(I::kPayloadPos);
  const Vec3<T> p_Q = x.template segment<3>(I::kQuadPos);
  const Vec3<T> v_L = x.template segment<3>(I::kPayloadVel);
  const Vec3<T> v_Q = x.template segment<3>(I::kQuadVel);
  const Vec3<T> r = p_L - p_Q;
  const T d = r.norm();
  const bool degenerate = !(d > T(1e-6));
  const Vec3<T> xi = degenerate ? Vec3<T>(T(0), T(0), T(-1)) : Vec3<T>(r / d);

  // positions: only as far as the taut band [l - epsilon, l] requires (the mode detector calls
  // a cable in it taut, and the taut flow's Baumgarte term closes the rest), same centre of mass
  T d_taut = d;
  if (d_taut < T(l - p.slack_epsilon_m)) d_taut = T(l - p.slack_epsilon_m);
  if (d_taut > T(l)) d_taut = T(l);
  Eigen::Matrix<T, kNx, 1> y = x;
  if (d_taut != d || degenerate) {
    const Vec3<T> p_com = (T(m) * p_Q + T(m_L) * p_L) / T(m + m_L);
    y.template segment<3>(I::kQuadPos) = p_com - T(m_L / (m + m_L)) * d_taut * xi;
    y.template segment<3>(I::kPayloadPos) = p_com + T(m / (m + m_L)) * d_taut * xi;
  }

  // velocities: a cable only pulls. A payload moving away along xi is stopped by a perfectly
  // inelastic collision (momentum kept); an approaching one gets no impulse
  const T v_rel = (v_L - v_Q).dot(xi);
  if (v_rel > T(0)) {
    const T v_c = (T(m) * v_Q.dot(xi) + T(m_L) * v_L.dot(xi)) / T(m + m_L);
    y.template segment<3>(I::kQuadVel) = v_Q + (v_c - v_Q.dot(xi)) * xi;
    y.template segment<3>(I::kPayloadVel) = v_L + (v_c - v_L.dot(xi)) * xi;
  }
  return y;
}

}  // namespace

HybridModel::HybridModel(const Params& params)
    : params_(params), allocation_(AllocationMatrix(params)) {}

StateVector HybridModel::Derivative(const StateVector& x, const InputVector& u,
                                    CableMode mode) const {
  return Flow<double>(params_, allocation_, x, u, mode);
}

void HybridModel::DerivativeJacobians(const StateVector& x, const InputVector& u, CableMode mode,
                                      StateVector* x_dot, StateMatrix* a, InputMatrix* b) const {
  Eigen::Matrix<AdScalar, kNx, 1> x_ad;
  Eigen::Matrix<AdScalar, kNu, 1> u_ad;
  Seed(x, u, &x_ad, &u_ad);
  Unpack(Flow<AdScalar>(params_, allocation_, x_ad, u_ad, mode), x_dot, a, b);
}

StateVector HybridModel::Step(const StateVector& x, const InputVector& u, CableMode mode,
                              double dt_s) const {
  return Rk4<double>(params_, allocation_, x, u, mode, dt_s);
}

void HybridModel::StepJacobians(const StateVector& x, const InputVector& u, CableMode mode,
                                double dt_s, StateVector* x_next, StateMatrix* a,
                                InputMatrix* b) const {
  Eigen::Matrix<AdScalar, kNx, 1> x_ad;
  Eigen::Matrix<AdScalar, kNu, 1> u_ad;
  Seed(x, u, &x_ad, &u_ad);
  Unpack(Rk4<AdScalar>(params_, allocation_, x_ad, u_ad, mode, dt_s), x_next, a, b);
}

StateVector HybridModel::ProjectToTaut(const StateVector& x) const {
  return JumpMap<double>(params_, x);
}

StateVector HybridModel::ProjectToTautJacobian(const StateVector& x, StateMatrix* jacobian) const {
  using JumpAd = Eigen::AutoDiffScalar<Eigen::Matrix<double, kNx, 1>>;
  Eigen::Matrix<JumpAd, kNx, 1> x_ad;
  for (int i = 0; i < kNx; ++i) x_ad(i) = JumpAd(x(i), kNx, i);
  const Eigen::Matrix<JumpAd, kNx, 1> y = JumpMap<JumpAd>(params_, x_ad);
  StateVector value;
  for (int i = 0; i < kNx; ++i) {
    value(i) = y(i).value();
    jacobian->row(i) = y(i).derivatives().transpose();
  }
  return value;
}

double HybridModel::TautTensionN(const StateVector& x, const InputVector& u) const {
  // m_L (a_L + g e3) = -T xi  =>  T = -m_L (a_L + g e3) . xi
  const StateVector x_dot = Derivative(x, u, CableMode::kTaut);
  const Eigen::Vector3d r =
      x.segment<3>(StateIndex::kPayloadPos) - x.segment<3>(StateIndex::kQuadPos);
  const Eigen::Vector3d a_L = x_dot.segment<3>(StateIndex::kPayloadVel);
  return -params_.payload_mass_kg *
         (a_L + Eigen::Vector3d(0, 0, params_.gravity_mps2)).dot(r.normalized());
}

StateVector HybridModel::HoverState(const Eigen::Vector3d& p_WQ_W) const {
  SystemState s;
  s.p_WQ_W = p_WQ_W;
  s.p_WL_W = p_WQ_W - Eigen::Vector3d(0, 0, params_.cable_length_m);
  return s.ToVector();
}

}  // namespace hpa
