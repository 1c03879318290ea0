#include "hpa/estimator/cable_ekf.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "gated_update.h"
#include "so3.h"

namespace hpa {
namespace {

// Renormalises xi and removes the radial part of xi_dot (the cable constraint).
void ProjectToConstraint(CableVector* x) {
  const double norm = x->head<3>().norm();
  if (norm > 1e-9) x->head<3>() /= norm;
  const Eigen::Vector3d xi = x->head<3>();
  x->tail<3>() -= xi.dot(x->tail<3>()) * xi;
}

}  // namespace

CableEkf::CableEkf(const Params& params, const CableEkfConfig& config, const Eigen::Vector3d& xi_W,
                   const Eigen::Vector3d& xi_dot_W, double time_s)
    : params_(params), config_(config) {
  CableMatrix covariance = CableMatrix::Zero();
  covariance.diagonal() << Eigen::Vector3d::Constant(std::pow(config.initial_xi_std, 2)),
      Eigen::Vector3d::Constant(std::pow(config.initial_xi_dot_std_per_s, 2));
  Reset(time_s, xi_W, xi_dot_W, covariance);
}

FilterStatus CableEkf::Refused(FilterStatus status) {
  counts_.CountRefused(status);
  return status;
}

void CableEkf::Reset(double time_s, const Eigen::Vector3d& xi_W, const Eigen::Vector3d& xi_dot_W,
                     const CableMatrix& covariance) {
  time_s_ = time_s;
  x_ << xi_W, xi_dot_W;
  ProjectToConstraint(&x_);
  covariance_ = covariance;
  consecutive_rejections_ = 0;
  history_.clear();
  history_.push_back({time_s_, x_, covariance_, 0.0, Eigen::Matrix3d::Identity()});
}

CableVector CableEkf::Derivative(const CableVector& x, const Eigen::Vector3d& force_W_N,
                                 double quad_mass_kg, double cable_length_m) {
  const Eigen::Vector3d xi = x.head<3>(), xi_dot = x.tail<3>();
  CableVector x_dot;
  x_dot << xi_dot,
      xi.cross(xi.cross(force_W_N)) / (quad_mass_kg * cable_length_m) - xi_dot.squaredNorm() * xi;
  return x_dot;
}

void CableEkf::Propagate(double dt_s, double thrust_N, const Eigen::Matrix3d& R_WB, CableVector* x,
                         CableMatrix* covariance) const {
  if (dt_s <= 0) return;
  if (dt_s > config_.max_step_s) {
    const int steps = static_cast<int>(std::ceil(dt_s / config_.max_step_s));
    for (int i = 0; i < steps; ++i) Propagate(dt_s / steps, thrust_N, R_WB, x, covariance);
    return;
  }
  const double m_kg = params_.quad_mass_kg, l_m = params_.cable_length_m;
  const Eigen::Vector3d u_N = thrust_N * R_WB.col(2);
  const Eigen::Vector3d xi = x->head<3>(), xi_dot = x->tail<3>();

  // Jacobian of the process model at the start of the step:
  // d/dxi [xi (xi.u) - u] / (m l) = ((xi.u) I + xi u^T) / (m l); d/dxi_dot |xi_dot|^2 xi = 2 xi
  // xi_dot^T
  CableMatrix A = CableMatrix::Zero();
  A.block<3, 3>(0, 3).setIdentity();
  A.block<3, 3>(3, 0) =
      (xi.dot(u_N) * Eigen::Matrix3d::Identity() + xi * u_N.transpose()) / (m_kg * l_m) -
      xi_dot.squaredNorm() * Eigen::Matrix3d::Identity();
  A.block<3, 3>(3, 3) = -2.0 * xi * xi_dot.transpose();
  const CableMatrix F = CableMatrix::Identity() + A * dt_s;

  // state: RK4, then back onto the constraint
  const CableVector k1 = Derivative(*x, u_N, m_kg, l_m);
  const CableVector k2 = Derivative(*x + 0.5 * dt_s * k1, u_N, m_kg, l_m);
  const CableVector k3 = Derivative(*x + 0.5 * dt_s * k2, u_N, m_kg, l_m);
  const CableVector k4 = Derivative(*x + dt_s * k3, u_N, m_kg, l_m);
  *x += dt_s / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
  ProjectToConstraint(x);

  *covariance = F * *covariance * F.transpose();
  covariance->diagonal().head<3>().array() += std::pow(config_.xi_noise_per_sqrts, 2) * dt_s;
  covariance->diagonal().tail<3>().array() += std::pow(config_.xi_ddot_noise_per_s15, 2) * dt_s;
}

FilterStatus CableEkf::Predict(double time_s, double thrust_N, const Eigen::Matrix3d& R_WB) {
  if (!std::isfinite(time_s) || !std::isfinite(thrust_N) || !R_WB.allFinite()) {
    return Refused(FilterStatus::kNonFinite);
  }
  if (time_s < time_s_) return Refused(FilterStatus::kOutOfOrder);
  Propagate(time_s - time_s_, thrust_N, R_WB, &x_, &covariance_);
  time_s_ = time_s;
  history_.push_back({time_s_, x_, covariance_, thrust_N, R_WB});
  while (history_.size() > 1 && history_.front().time_s < time_s_ - config_.history_s) {
    history_.pop_front();
  }
  return FilterStatus::kOk;
}

template <typename Fuse>
FilterStatus CableEkf::FuseAtCaptureTime(double capture_time_s, const Fuse& fuse) {
  // latest kept entry at or before the capture time
  auto it = std::upper_bound(history_.begin(), history_.end(), capture_time_s,
                             [](double t, const Entry& e) { return t < e.time_s; });
  if (it == history_.begin()) return Refused(FilterStatus::kTooOld);
  const size_t k = static_cast<size_t>(std::distance(history_.begin(), it)) - 1;
  CableVector x = history_[k].x;
  CableMatrix covariance = history_[k].covariance;
  const FilterStatus status = fuse(&x, &covariance);
  if (status != FilterStatus::kOk) return status;
  ProjectToConstraint(&x);
  history_[k].x = x;
  history_[k].covariance = covariance;

  // re-propagate the stored inputs
  for (size_t j = k + 1; j < history_.size(); ++j) {
    Propagate(history_[j].time_s - history_[j - 1].time_s, history_[j].thrust_N, history_[j].R_WB,
              &x, &covariance);
    history_[j].x = x;
    history_[j].covariance = covariance;
  }
  x_ = x;
  covariance_ = covariance;
  return FilterStatus::kOk;
}

FilterStatus CableEkf::Update(double capture_time_s, const Eigen::Vector3d& p_BL_B,
                              const Eigen::Matrix3d& R_WB, const Eigen::Matrix3d& cov_B_m2) {
  if (!std::isfinite(capture_time_s) || !p_BL_B.allFinite() || !R_WB.allFinite() ||
      !cov_B_m2.allFinite()) {
    return Refused(FilterStatus::kNonFinite);
  }
  return FuseAtCaptureTime(capture_time_s, [&](CableVector* x, CableMatrix* covariance) {
    // h(x) = R^T l xi, H = [R^T l, 0]
    const double l_m = params_.cable_length_m;
    const Eigen::Vector3d r = p_BL_B - R_WB.transpose() * l_m * x->head<3>();
    Eigen::Matrix<double, 3, 6> H = Eigen::Matrix<double, 3, 6>::Zero();
    H.block<3, 3>(0, 0) = R_WB.transpose() * l_m;
    const GatedUpdateResult<6> update =
        GatedKalmanUpdate<6, 3>(r, H, cov_B_m2, config_.gate, GainProduct::kHP,
                                &consecutive_rejections_, covariance, &counts_);
    if (update.status == FilterStatus::kOk) *x += update.dx;
    return update.status;
  });
}

FilterStatus CableEkf::UpdateVelocity(double capture_time_s, const Eigen::Vector3d& v_BL_B,
                                      const Eigen::Matrix3d& R_WB, const Eigen::Vector3d& w_B_radps,
                                      const Eigen::Matrix3d& cov_B) {
  if (!std::isfinite(capture_time_s) || !v_BL_B.allFinite() || !R_WB.allFinite() ||
      !w_B_radps.allFinite() || !cov_B.allFinite()) {
    return Refused(FilterStatus::kNonFinite);
  }
  return FuseAtCaptureTime(capture_time_s, [&](CableVector* x, CableMatrix* covariance) {
    // h(x) = l (R^T xi_dot - w x R^T xi), H = [-l [w]x R^T, l R^T]
    const double l_m = params_.cable_length_m;
    const Eigen::Matrix3d Rt = R_WB.transpose();
    const Eigen::Vector3d xi_B = Rt * x->head<3>();
    const Eigen::Vector3d r = v_BL_B - l_m * (Rt * x->tail<3>() - w_B_radps.cross(xi_B));
    Eigen::Matrix<double, 3, 6> H;
    H << -l_m * Skew(w_B_radps) * Rt, l_m * Rt;
    const GatedUpdateResult<6> update =
        GatedKalmanUpdate<6, 3>(r, H, cov_B, config_.gate, GainProduct::kHP,
                                &consecutive_rejections_, covariance, &counts_);
    if (update.status == FilterStatus::kOk) *x += update.dx;
    return update.status;
  });
}

}  // namespace hpa
