#include "hpa/estimator/quad_filter.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "gated_update.h"
#include "so3.h"

namespace hpa {
namespace {

// A VIO quaternion shorter than this carries no attitude (a zero-initialised message).
constexpr double kMinQuaternionNorm = 1e-6;

}  // namespace

QuadFilterState QuadFilterStateFrom(const SystemState& state) {
  QuadFilterState q;
  q.time_s = state.time_s;
  q.p_WB_W = state.p_WQ_W;
  q.v_WB_W = state.v_WQ_W;
  q.q_WB = state.q_WB;
  q.w_B_radps = state.w_B;
  return q;
}

FilterStatus QuadFilter::Refused(FilterStatus status) {
  counts_.CountRefused(status);
  return status;
}

QuadFilter::QuadFilter(const Params& params, const QuadFilterConfig& config,
                       const QuadFilterState& initial)
    : params_(params), config_(config), state_(initial) {
  state_.q_WB.normalize();
  Vector15d sigma;
  sigma << Eigen::Vector3d::Constant(config.initial_position_std_m),
      Eigen::Vector3d::Constant(config.initial_velocity_std_mps),
      Eigen::Vector3d::Constant(config.initial_attitude_std_rad),
      Eigen::Vector3d::Constant(config.initial_gyro_bias_std_radps),
      Eigen::Vector3d::Constant(config.initial_accel_bias_std_mps2);
  covariance_ = sigma.cwiseAbs2().asDiagonal();
}

void QuadFilter::Propagate(const ImuSample& previous, const ImuSample& imu, QuadFilterState* state,
                           Matrix15d* covariance) const {
  const double dt_s = imu.time_s - state->time_s;
  if (dt_s <= 0) return;
  // trapezoid of the two samples, bias-corrected
  const Eigen::Vector3d w_B =
      0.5 * (previous.gyro_B_radps + imu.gyro_B_radps) - state->gyro_bias_B_radps;
  const Eigen::Vector3d a_B =
      0.5 * (previous.accel_B_mps2 + imu.accel_B_mps2) - state->accel_bias_B_mps2;
  const Eigen::Matrix3d R_WB = state->q_WB.toRotationMatrix();
  const Eigen::Matrix3d dR = ExpSo3(w_B * dt_s);

  // nominal state: specific force rotated with the mid-step attitude
  const Eigen::Vector3d a_W =
      R_WB * ExpSo3(0.5 * w_B * dt_s) * a_B - Eigen::Vector3d(0, 0, params_.gravity_mps2);
  state->p_WB_W += state->v_WB_W * dt_s + 0.5 * a_W * dt_s * dt_s;
  state->v_WB_W += a_W * dt_s;
  state->q_WB = Eigen::Quaterniond(R_WB * dR).normalized();
  state->w_B_radps = imu.gyro_B_radps - state->gyro_bias_B_radps;
  state->time_s = imu.time_s;

  // error-state transition (first order) and discrete process noise
  Matrix15d F = Matrix15d::Identity();
  F.block<3, 3>(0, 3) = Eigen::Matrix3d::Identity() * dt_s;
  F.block<3, 3>(3, 6) = -R_WB * Skew(a_B) * dt_s;
  F.block<3, 3>(3, 12) = -R_WB * dt_s;
  F.block<3, 3>(6, 6) = dR.transpose();
  F.block<3, 3>(6, 9) = -Eigen::Matrix3d::Identity() * dt_s;
  Vector15d q;
  q << Eigen::Vector3d::Zero(),
      Eigen::Vector3d::Constant(std::pow(config_.accel_noise_mps2_per_sqrthz, 2) * dt_s),
      Eigen::Vector3d::Constant(std::pow(config_.gyro_noise_radps_per_sqrthz, 2) * dt_s),
      Eigen::Vector3d::Constant(std::pow(config_.gyro_bias_walk_radps2_per_sqrthz, 2) * dt_s),
      Eigen::Vector3d::Constant(std::pow(config_.accel_bias_walk_mps3_per_sqrthz, 2) * dt_s);
  *covariance = F * *covariance * F.transpose();
  covariance->diagonal() += q;
}

FilterStatus QuadFilter::Predict(const ImuSample& imu) {
  if (!std::isfinite(imu.time_s) || !imu.gyro_B_radps.allFinite() ||
      !imu.accel_B_mps2.allFinite()) {
    return Refused(FilterStatus::kNonFinite);
  }
  if (imu.time_s <= state_.time_s && last_imu_) return Refused(FilterStatus::kOutOfOrder);
  Propagate(last_imu_ ? *last_imu_ : imu, imu, &state_, &covariance_);
  if (!last_imu_) state_.w_B_radps = imu.gyro_B_radps - state_.gyro_bias_B_radps;
  last_imu_ = imu;
  history_.push_back({state_, covariance_, imu});
  while (!history_.empty() && history_.front().state.time_s < state_.time_s - config_.history_s) {
    history_.pop_front();
  }
  return FilterStatus::kOk;
}

FilterStatus QuadFilter::Correct(const VioSample& vio, QuadFilterState* state,
                                 Matrix15d* covariance) {
  // residual [p; theta; v] with the attitude residual on the right of the estimate
  Eigen::Matrix<double, 9, 1> r;
  r << vio.p_WB_W - state->p_WB_W,
      LogSo3(state->q_WB.toRotationMatrix().transpose() * vio.q_WB.normalized().toRotationMatrix()),
      vio.v_WB_W - state->v_WB_W;
  Eigen::Matrix<double, 9, 15> H = Eigen::Matrix<double, 9, 15>::Zero();
  H.block<3, 3>(0, 0).setIdentity();
  H.block<3, 3>(3, 6).setIdentity();
  H.block<3, 3>(6, 3).setIdentity();
  Eigen::Matrix<double, 9, 1> noise_var;
  noise_var << Eigen::Vector3d::Constant(std::pow(config_.vio_position_std_m, 2)),
      Eigen::Vector3d::Constant(std::pow(config_.vio_attitude_std_rad, 2)),
      Eigen::Vector3d::Constant(std::pow(config_.vio_velocity_std_mps, 2));
  const Eigen::Matrix<double, 9, 9> Rn = noise_var.asDiagonal();
  const GatedUpdateResult<15> update =
      GatedKalmanUpdate<15, 9>(r, H, Rn, config_.vio_gate, GainProduct::kHPTransposed,
                               &consecutive_rejections_, covariance, &counts_);
  if (update.status != FilterStatus::kOk) return update.status;
  const Vector15d& dx = update.dx;

  // inject the error into the nominal state and reset it to zero
  state->p_WB_W += dx.segment<3>(0);
  state->v_WB_W += dx.segment<3>(3);
  state->q_WB =
      Eigen::Quaterniond(state->q_WB.toRotationMatrix() * ExpSo3(dx.segment<3>(6))).normalized();
  state->gyro_bias_B_radps += dx.segment<3>(9);
  state->accel_bias_B_mps2 += dx.segment<3>(12);
  Matrix15d G = Matrix15d::Identity();
  G.block<3, 3>(6, 6) -= 0.5 * Skew(dx.segment<3>(6));
  *covariance = G * *covariance * G.transpose();
  return FilterStatus::kOk;
}

FilterStatus QuadFilter::UpdateVio(const VioSample& vio) {
  if (!std::isfinite(vio.time_s) || !vio.p_WB_W.allFinite() || !vio.v_WB_W.allFinite() ||
      !vio.q_WB.coeffs().allFinite() || vio.q_WB.norm() < kMinQuaternionNorm) {
    return Refused(FilterStatus::kNonFinite);
  }
  // newer than the latest IMU sample (or no history): correct the current state
  if (history_.empty() || vio.time_s >= state_.time_s) {
    const FilterStatus status = Correct(vio, &state_, &covariance_);
    if (status == FilterStatus::kOk && !history_.empty()) {
      history_.back().state = state_;
      history_.back().covariance = covariance_;
    }
    return status;
  }
  // latest kept entry at or before the capture time
  auto it = std::upper_bound(history_.begin(), history_.end(), vio.time_s,
                             [](double t, const Entry& e) { return t < e.state.time_s; });
  if (it == history_.begin()) return Refused(FilterStatus::kTooOld);
  size_t k = static_cast<size_t>(std::distance(history_.begin(), it)) - 1;
  QuadFilterState state = history_[k].state;
  Matrix15d covariance = history_[k].covariance;
  const FilterStatus status = Correct(vio, &state, &covariance);
  if (status != FilterStatus::kOk) return status;
  history_[k].state = state;
  history_[k].covariance = covariance;

  // re-propagate the newer IMU samples from the corrected entry
  for (size_t j = k + 1; j < history_.size(); ++j) {
    Propagate(history_[j - 1].imu, history_[j].imu, &state, &covariance);
    history_[j].state = state;
    history_[j].covariance = covariance;
  }
  state_ = state;
  covariance_ = covariance;
  return FilterStatus::kOk;
}

std::optional<QuadFilterState> QuadFilter::StateAt(double time_s) const {
  if (time_s >= state_.time_s) return state_;
  auto it = std::upper_bound(history_.begin(), history_.end(), time_s,
                             [](double t, const Entry& e) { return t < e.state.time_s; });
  if (it == history_.begin()) return std::nullopt;
  return std::prev(it)->state;
}

Vector15d QuadFilter::ErrorState(const QuadFilterState& estimate, const QuadFilterState& truth) {
  Vector15d e;
  e << truth.p_WB_W - estimate.p_WB_W, truth.v_WB_W - estimate.v_WB_W,
      LogSo3(estimate.q_WB.toRotationMatrix().transpose() * truth.q_WB.toRotationMatrix()),
      truth.gyro_bias_B_radps - estimate.gyro_bias_B_radps,
      truth.accel_bias_B_mps2 - estimate.accel_bias_B_mps2;
  return e;
}

}  // namespace hpa
