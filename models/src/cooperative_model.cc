#include "hpa/models/cooperative_model.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <stdexcept>
#include <string>

#include "hpa/models/hybrid_model.h"
#include "hpa/models/rotor_model.h"

namespace hpa {
namespace {

using I = CooperativeStateIndex;
using Eigen::Matrix3d;
using Eigen::Vector3d;

// Skew matrix: Hat(a) b = a x b.
Matrix3d Hat(const Vector3d& a) {
  Matrix3d m;
  m << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return m;
}

// Rotation of a (w, x, y, z) quaternion stored at x(at), normalised as RotorTM's QuatToRot does.
Matrix3d Rotation(const Eigen::VectorXd& x, int at) {
  return Eigen::Quaterniond(x(at), x(at + 1), x(at + 2), x(at + 3)).normalized().toRotationMatrix();
}

// q_dot = 1/2 q (x) [0, w_body] for a (w, x, y, z) quaternion.
Eigen::Vector4d QuaternionRate(const Eigen::Vector4d& q, const Vector3d& w) {
  Eigen::Vector4d q_dot;
  q_dot << -0.5 * (q(1) * w(0) + q(2) * w(1) + q(3) * w(2)),
      0.5 * (q(0) * w(0) + q(2) * w(2) - q(3) * w(1)),
      0.5 * (q(0) * w(1) + q(3) * w(0) - q(1) * w(2)),
      0.5 * (q(0) * w(2) + q(1) * w(1) - q(2) * w(0));
  return q_dot;
}

// One cable's geometry at x: direction, attachment velocity, and the centripetal term.
struct CableGeometry {
  Vector3d xi;                  // unit, vehicle to attachment, world  (3)
  Vector3d rho_P;               // attachment point, payload frame  (3)
  Vector3d u_W;                 // vehicle's thrust vector f R e3, world  (3)
  double centripetal_mps2 = 0;  // l |xi x xi_dot|^2 on the constraint, Baumgarte-stabilised off it
  double v_r_mps = 0;           // rate of change of the cable's span
  double span_m = 0;            // |p_A - p_Q|
};

CableGeometry Geometry(const CooperativeVehicle& v, const Eigen::VectorXd& x, int i,
                       const Eigen::VectorXd& u) {
  const Matrix3d R_WP = Rotation(x, I::kPayloadQuat);
  const Vector3d w_P = x.segment<3>(I::kPayloadRate);
  const int b = I::Vehicle(i);
  CableGeometry g;
  g.rho_P = v.p_PA_P_m;
  const Vector3d p_WA_W = x.segment<3>(I::kPayloadPos) + R_WP * g.rho_P;
  const Vector3d v_WA_W = x.segment<3>(I::kPayloadVel) + R_WP * w_P.cross(g.rho_P);
  const Vector3d r = p_WA_W - x.segment<3>(b + I::kVehiclePos);
  g.span_m = r.norm();
  g.xi = r / g.span_m;
  const Vector3d v_rel = v_WA_W - x.segment<3>(b + I::kVehicleVel);
  g.v_r_mps = v_rel.dot(g.xi);
  const double v_perp_sq = v_rel.squaredNorm() - g.v_r_mps * g.v_r_mps;
  g.centripetal_mps2 = v_perp_sq / g.span_m + HybridModel::kBaumgarteDamping * g.v_r_mps +
                       HybridModel::kBaumgarteStiffness * (g.span_m - v.cable_length_m);
  const double thrust_N = WrenchFromRotorSpeeds(v.params, u.segment<4>(4 * i))(0);
  g.u_W = thrust_N * Rotation(x, b + I::kVehicleQuat).col(2);
  return g;
}

// The flow and the tensions it implies (RotorTM, rotor_tm_sim/src/rotor_tm_sim/
// simulation_base.py, hybrid_cooperative_rigidbody_pl_transportationEOM with
// rigidbody_payloadEOM_readonly, taut_quadEOM_readonly and slack_quadEOM_readonly).
Eigen::VectorXd Flow(const CooperativeTeam& team, const Eigen::VectorXd& x,
                     const Eigen::VectorXd& u, const std::vector<CableMode>& modes,
                     Eigen::VectorXd* tensions_N) {
  const int n = static_cast<int>(team.vehicles.size());
  if (x.size() != I::Size(n) || u.size() != 4 * n || static_cast<int>(modes.size()) != n) {
    throw std::invalid_argument("cooperative model: state, input or modes of the wrong size");
  }
  const Vector3d e3(0, 0, 1);
  const Matrix3d R_WP = Rotation(x, I::kPayloadQuat);
  const Vector3d w_P = x.segment<3>(I::kPayloadRate);
  const Matrix3d w_hat = Hat(w_P);

  // payload: effective mass ML, net force F (world) and moment M (payload frame) of the taut
  // cables, and the couplings C, D, E between the payload's linear and angular accelerations
  Matrix3d ML = team.payload_mass_kg * Matrix3d::Identity();
  Matrix3d C = Matrix3d::Zero(), D = Matrix3d::Zero(), E = Matrix3d::Zero();
  Vector3d F = Vector3d::Zero(), M = Vector3d::Zero();
  std::vector<CableGeometry> cables(n);
  for (int i = 0; i < n; ++i) {
    if (modes[i] != CableMode::kTaut) continue;
    const CooperativeVehicle& v = team.vehicles[i];
    const double m = v.params.quad_mass_kg;
    const CableGeometry& g = cables[i] = Geometry(v, x, i, u);
    const Matrix3d xixiT = g.xi * g.xi.transpose();
    const Matrix3d rho_hat = Hat(g.rho_P);
    const Vector3d a_centrifugal_W = R_WP * (w_hat * (w_hat * g.rho_P));
    const Vector3d f_attach =
        xixiT * g.u_W - m * g.centripetal_mps2 * g.xi - m * xixiT * a_centrifugal_W;
    F += f_attach;
    M += rho_hat * R_WP.transpose() * f_attach;
    const Matrix3d Ck = m * rho_hat * R_WP.transpose() * xixiT;
    C += Ck;
    D -= Ck.transpose();
    E += Ck * R_WP * rho_hat;
    ML += m * xixiT;
  }

  // payload accelerations: angular from the effective inertia, then linear
  const Matrix3d J = team.payload_inertia_P_kgm2.asDiagonal();
  const Matrix3d ML_inv = ML.inverse();
  const Vector3d M_eff = M - C * ML_inv * F - w_P.cross(J * w_P);
  const Matrix3d J_eff = J + C * ML_inv * D - E;
  const Vector3d w_dot_P = J_eff.partialPivLu().solve(M_eff);
  const Vector3d a_L = ML_inv * (F + D * w_dot_P) - team.gravity_mps2 * e3;

  Eigen::VectorXd x_dot(x.size());
  x_dot.segment<3>(I::kPayloadPos) = x.segment<3>(I::kPayloadVel);
  x_dot.segment<3>(I::kPayloadVel) = a_L;
  x_dot.segment<4>(I::kPayloadQuat) = QuaternionRate(x.segment<4>(I::kPayloadQuat), w_P);
  x_dot.segment<3>(I::kPayloadRate) = w_dot_P;
  if (tensions_N != nullptr) *tensions_N = Eigen::VectorXd::Zero(n);

  // vehicles: HybridModel's quadrotor with the payload's slot unused (slack), plus the tension
  // along xi for a taut cable, the attachment's acceleration taken from the payload's
  for (int i = 0; i < n; ++i) {
    const CooperativeVehicle& v = team.vehicles[i];
    const int b = I::Vehicle(i);
    StateVector x19 = StateVector::Zero();
    x19.segment<I::kBlockSize>(StateIndex::kQuadPos) = x.segment<I::kBlockSize>(b);
    const StateVector x19_dot =
        HybridModel(v.params).Derivative(x19, u.segment<4>(4 * i), CableMode::kSlack);
    x_dot.segment<I::kBlockSize>(b) = x19_dot.segment<I::kBlockSize>(StateIndex::kQuadPos);
    if (modes[i] != CableMode::kTaut) continue;
    const CableGeometry& g = cables[i];
    const double m = v.params.quad_mass_kg;
    const Vector3d a_attach = a_L + team.gravity_mps2 * e3 + R_WP * (Hat(w_dot_P) * g.rho_P) +
                              R_WP * (w_hat * (w_hat * g.rho_P));
    const double tension_N = m * g.centripetal_mps2 - g.xi.dot(g.u_W - m * a_attach);
    x_dot.segment<3>(b + I::kVehicleVel) += tension_N / m * g.xi;
    if (tensions_N != nullptr) (*tensions_N)(i) = tension_N;
  }
  return x_dot;
}

// Every quaternion of the state (payload and vehicles) scaled to unit norm.
void NormaliseQuaternions(int n, Eigen::VectorXd* x) {
  x->segment<4>(I::kPayloadQuat).normalize();
  for (int i = 0; i < n; ++i) x->segment<4>(I::Vehicle(i) + I::kVehicleQuat).normalize();
}

}  // namespace

CooperativeTeam CooperativeTeam::SingleVehicle(const Params& params) {
  CooperativeTeam team;
  team.payload_mass_kg = params.payload_mass_kg;
  team.gravity_mps2 = params.gravity_mps2;
  CooperativeVehicle v;
  v.params = params;
  v.cable_length_m = params.cable_length_m;
  team.vehicles.push_back(v);
  return team;
}

CooperativeModel::CooperativeModel(CooperativeTeam team) : team_(std::move(team)) {
  if (team_.vehicles.empty()) throw std::invalid_argument("a cooperative team needs a vehicle");
  if (!(team_.payload_mass_kg > 0) || !(team_.payload_inertia_P_kgm2.minCoeff() > 0)) {
    throw std::invalid_argument("the payload's mass and inertia must be positive");
  }
  for (std::size_t i = 0; i < team_.vehicles.size(); ++i) {
    const CooperativeVehicle& v = team_.vehicles[i];
    if (!(v.cable_length_m > 0) || !(v.params.quad_mass_kg > 0) || !v.p_PA_P_m.allFinite()) {
      throw std::invalid_argument("vehicle " + std::to_string(i) +
                                  ": cable length and mass must be positive, attachment finite");
    }
  }
}

Eigen::VectorXd CooperativeModel::Derivative(const Eigen::VectorXd& x, const Eigen::VectorXd& u,
                                             const std::vector<CableMode>& modes) const {
  return Flow(team_, x, u, modes, nullptr);
}

Eigen::VectorXd CooperativeModel::Step(const Eigen::VectorXd& x, const Eigen::VectorXd& u,
                                       const std::vector<CableMode>& modes, double dt_s) const {
  const Eigen::VectorXd k1 = Flow(team_, x, u, modes, nullptr);
  const Eigen::VectorXd k2 = Flow(team_, x + 0.5 * dt_s * k1, u, modes, nullptr);
  const Eigen::VectorXd k3 = Flow(team_, x + 0.5 * dt_s * k2, u, modes, nullptr);
  const Eigen::VectorXd k4 = Flow(team_, x + dt_s * k3, u, modes, nullptr);
  Eigen::VectorXd x_next = x + dt_s / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
  NormaliseQuaternions(VehicleCount(), &x_next);
  return x_next;
}

Eigen::VectorXd CooperativeModel::CableTensionsN(const Eigen::VectorXd& x, const Eigen::VectorXd& u,
                                                 const std::vector<CableMode>& modes) const {
  Eigen::VectorXd tensions_N;
  Flow(team_, x, u, modes, &tensions_N);
  return tensions_N;
}

std::vector<bool> CooperativeModel::RetautingCables(const Eigen::VectorXd& x, double taut_band_m,
                                                    double speed_threshold_mps) const {
  std::vector<bool> retauting(VehicleCount());
  const Eigen::VectorXd u = Eigen::VectorXd::Zero(4 * VehicleCount());
  for (int i = 0; i < VehicleCount(); ++i) {
    const CableGeometry g = Geometry(team_.vehicles[i], x, i, u);
    retauting[i] = g.span_m > team_.vehicles[i].cable_length_m - taut_band_m &&
                   g.v_r_mps > speed_threshold_mps;
  }
  return retauting;
}

Eigen::VectorXd CooperativeModel::RetautCollision(const Eigen::VectorXd& x,
                                                  const std::vector<bool>& colliding) const {
  // RotorTM, simulation_base.py, rigidbody_quad_inelastic_cable_collision: the payload's
  // generalised velocity [v_L; w_P] solves (M_L + G M_Q G^T) [v_L; w_P]+ = M_L [v_L; w_P]- +
  // G M_Q (xi . v_Q-), G's column k = [xi_k; rho_k x R^T xi_k]; each colliding vehicle keeps its
  // velocity across the cable and takes its attachment's along it
  const Matrix3d R_WP = Rotation(x, I::kPayloadQuat);
  Eigen::Matrix<double, 6, 6> M_sys = Eigen::Matrix<double, 6, 6>::Zero();
  M_sys.topLeftCorner<3, 3>() = team_.payload_mass_kg * Matrix3d::Identity();
  M_sys.bottomRightCorner<3, 3>() = team_.payload_inertia_P_kgm2.asDiagonal();
  Eigen::Matrix<double, 6, 1> rhs;
  rhs << team_.payload_mass_kg * x.segment<3>(I::kPayloadVel),
      team_.payload_inertia_P_kgm2.cwiseProduct(x.segment<3>(I::kPayloadRate));
  const Eigen::VectorXd u = Eigen::VectorXd::Zero(4 * VehicleCount());
  std::vector<CableGeometry> cables(VehicleCount());
  for (int i = 0; i < VehicleCount(); ++i) {
    if (!colliding[i]) continue;
    cables[i] = Geometry(team_.vehicles[i], x, i, u);
    const CableGeometry& g = cables[i];
    const double m = team_.vehicles[i].params.quad_mass_kg;
    Eigen::Matrix<double, 6, 1> G;
    G << g.xi, g.rho_P.cross(R_WP.transpose() * g.xi);
    M_sys += m * G * G.transpose();
    rhs += m * G * g.xi.dot(x.segment<3>(I::Vehicle(i) + I::kVehicleVel));
  }
  const Eigen::Matrix<double, 6, 1> vw = M_sys.ldlt().solve(rhs);

  Eigen::VectorXd y = x;
  y.segment<3>(I::kPayloadVel) = vw.head<3>();
  y.segment<3>(I::kPayloadRate) = vw.tail<3>();
  for (int i = 0; i < VehicleCount(); ++i) {
    if (!colliding[i]) continue;
    const CableGeometry& g = cables[i];
    const Vector3d v_WA_W = vw.head<3>() + R_WP * vw.tail<3>().cross(g.rho_P);
    const int at = I::Vehicle(i) + I::kVehicleVel;
    const Vector3d v_Q = x.segment<3>(at);
    y.segment<3>(at) = v_Q - g.xi.dot(v_Q) * g.xi + g.xi.dot(v_WA_W) * g.xi;
  }
  return y;
}

Eigen::VectorXd CooperativeModel::HangingState(const Eigen::Vector3d& p_WL_W) const {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(StateSize());
  x.segment<3>(I::kPayloadPos) = p_WL_W;
  x(I::kPayloadQuat) = 1;
  for (int i = 0; i < VehicleCount(); ++i) {
    const CooperativeVehicle& v = team_.vehicles[i];
    x.segment<3>(I::Vehicle(i) + I::kVehiclePos) =
        p_WL_W + v.p_PA_P_m + Vector3d(0, 0, v.cable_length_m);
    x(I::Vehicle(i) + I::kVehicleQuat) = 1;
  }
  return x;
}

Eigen::VectorXd CooperativeModel::FromSingleVehicleState(const StateVector& x19) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(I::Size(1));
  x.segment<3>(I::kPayloadPos) = x19.segment<3>(StateIndex::kPayloadPos);
  x.segment<3>(I::kPayloadVel) = x19.segment<3>(StateIndex::kPayloadVel);
  x(I::kPayloadQuat) = 1;
  x.segment<I::kBlockSize>(I::Vehicle(0)) = x19.segment<I::kBlockSize>(StateIndex::kQuadPos);
  return x;
}

}  // namespace hpa
