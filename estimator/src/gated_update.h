#pragma once
// The gated Kalman measurement update shared by the quadrotor filter, the cable EKF and the
// payload tracker: innovation covariance S = H P H^T + R, chi-square gate on the normalised
// innovation squared with a forced accept after a run of rejections, gain K = P H^T S^-1 and the
// Joseph-form covariance update. The caller forms the residual and applies the correction K r
// to its own state (vector addition, manifold retraction, constraint projection).

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "hpa/estimator/filter_status.h"

namespace hpa {

/// Which product forms the gain's right-hand side S^-1 (H P) or S^-1 (H P^T). Equal in exact
/// arithmetic (P is symmetric), but an updated covariance is not bitwise symmetric, so each
/// filter keeps the rounding it was tuned and recorded with.
enum class GainProduct { kHP, kHPTransposed };

/// What one gated update did.
template <int N>
struct GatedUpdateResult {
  FilterStatus status = FilterStatus::kOk;  // kOk, kRejected, kNonFinite (S non-finite/singular)
  double nis = 0.0;                         // r^T S^-1 r (0 when S could not be factored)
  bool forced = false;                      // fused although nis exceeded the gate
  Eigen::Matrix<double, N, 1> dx = Eigen::Matrix<double, N, 1>::Zero();  // K r, zero unless kOk
};

/// Gated update of an N-state filter with an M-dimensional measurement: residual r (M), Jacobian
/// H (M x N), noise covariance R (M x M). On kOk the covariance (N x N) is updated in place and
/// the correction returned in dx; otherwise nothing but the gate's run counter and `counts`
/// change.
template <int N, int M>
GatedUpdateResult<N> GatedKalmanUpdate(
    const Eigen::Matrix<double, M, 1>& r, const Eigen::Matrix<double, M, N>& H,
    const Eigen::Matrix<double, M, M>& R, const InnovationGate& gate, GainProduct gain_product,
    int* consecutive_rejections, Eigen::Matrix<double, N, N>* covariance, FilterCounts* counts) {
  using MatrixNN = Eigen::Matrix<double, N, N>;
  using MatrixNM = Eigen::Matrix<double, N, M>;
  using MatrixMM = Eigen::Matrix<double, M, M>;
  GatedUpdateResult<N> result;

  // innovation covariance
  const MatrixMM S = H * *covariance * H.transpose() + R;
  const Eigen::LDLT<MatrixMM> S_ldlt(S);
  if (!S.allFinite() || S_ldlt.info() != Eigen::Success) {
    ++counts->non_finite;
    result.status = FilterStatus::kNonFinite;
    return result;
  }

  // chi-square gate; a run of max_consecutive_rejections rejections forces the next accept
  result.nis = r.dot(S_ldlt.solve(r));
  counts->last_nis = result.nis;
  if (result.nis > gate.nis_threshold &&
      *consecutive_rejections < gate.max_consecutive_rejections) {
    ++*consecutive_rejections;
    ++counts->rejected_updates;
    result.status = FilterStatus::kRejected;
    return result;
  }
  result.forced = result.nis > gate.nis_threshold;
  *consecutive_rejections = 0;
  ++counts->accepted_updates;
  if (result.forced) ++counts->forced_accepts;

  // gain P H^T S^-1 (P symmetric), correction, Joseph-form covariance
  MatrixNM K;
  if (gain_product == GainProduct::kHP) {
    K = S_ldlt.solve(H * *covariance).transpose();
  } else {
    K = S_ldlt.solve(H * covariance->transpose()).transpose();
  }
  result.dx = K * r;
  const MatrixNN I_KH = MatrixNN::Identity() - K * H;
  *covariance = I_KH * *covariance * I_KH.transpose() + K * R * K.transpose();
  return result;
}

}  // namespace hpa
