// The gated Kalman update shared by the three filters, against the textbook update and the
// gate's closed-form NIS.
#include "estimator/src/gated_update.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>

namespace hpa {
namespace {

using Matrix2d = Eigen::Matrix2d;
using Matrix23 = Eigen::Matrix<double, 2, 3>;
using Matrix3d = Eigen::Matrix3d;

// A 3-state filter measuring its first two states.
struct Problem {
  Matrix3d P = Eigen::Vector3d(0.04, 0.09, 0.25).asDiagonal();
  Matrix23 H = (Matrix23() << 1, 0, 0, 0, 1, 0).finished();
  Matrix2d R = Eigen::Vector2d(0.01, 0.01).asDiagonal();
};

TEST(GatedUpdateTest, NisAndUpdateMatchTheTextbookForms) {
  Problem p;
  p.P(0, 2) = p.P(2, 0) = 0.05;  // the unmeasured state is correlated with the first
  const Eigen::Vector2d r(0.1, -0.2);
  const InnovationGate gate{100.0, 3};
  int consecutive = 0;
  FilterCounts counts;
  Matrix3d P = p.P;
  const GatedUpdateResult<3> u =
      GatedKalmanUpdate<3, 2>(r, p.H, p.R, gate, GainProduct::kHP, &consecutive, &P, &counts);
  ASSERT_EQ(u.status, FilterStatus::kOk);
  EXPECT_FALSE(u.forced);
  // S is diagonal here: NIS = 0.1^2 / 0.05 + 0.2^2 / 0.1 = 0.6
  EXPECT_NEAR(u.nis, 0.6, 1e-14);
  EXPECT_EQ(counts.last_nis, u.nis);
  // K = P H^T S^-1, dx = K r, P+ = (I - K H) P (Joseph equals it for the optimal gain); the
  // forms differ by rounding only, 1e-14 on entries of order 0.1
  const Matrix2d S = p.H * p.P * p.H.transpose() + p.R;
  const Eigen::Matrix<double, 3, 2> K = p.P * p.H.transpose() * S.inverse();
  EXPECT_LT((u.dx - K * r).norm(), 1e-14);
  EXPECT_LT((P - (Matrix3d::Identity() - K * p.H) * p.P).norm(), 1e-14);
  EXPECT_EQ(counts.accepted_updates, 1);
  EXPECT_EQ(counts.rejected_updates, 0);
}

TEST(GatedUpdateTest, BothGainProductsAgreeOnASymmetricCovariance) {
  Problem p;
  p.P(0, 1) = p.P(1, 0) = 0.02;
  const Eigen::Vector2d r(0.05, 0.03);
  int consecutive = 0;
  FilterCounts counts;
  Matrix3d P_hp = p.P, P_hpt = p.P;
  const auto a = GatedKalmanUpdate<3, 2>(r, p.H, p.R, InnovationGate{}, GainProduct::kHP,
                                         &consecutive, &P_hp, &counts);
  const auto b = GatedKalmanUpdate<3, 2>(r, p.H, p.R, InnovationGate{}, GainProduct::kHPTransposed,
                                         &consecutive, &P_hpt, &counts);
  // P is exactly symmetric, so H P and H P^T hold the same numbers
  EXPECT_EQ(a.dx, b.dx);
  EXPECT_EQ(P_hp, P_hpt);
}

TEST(GatedUpdateTest, RejectsOverTheGateThenForcesAnAcceptAfterTheRun) {
  const Problem p;
  const InnovationGate gate{9.0, 2};
  const Eigen::Vector2d wild(1.0, 1.0);  // NIS = 1 / 0.05 + 1 / 0.1 = 30 > 9
  const Eigen::Vector2d fair(0.1, 0.1);  // NIS = 0.3
  int consecutive = 0;
  FilterCounts counts;
  Matrix3d P = p.P;
  for (int k = 1; k <= 2; ++k) {
    const auto u =
        GatedKalmanUpdate<3, 2>(wild, p.H, p.R, gate, GainProduct::kHP, &consecutive, &P, &counts);
    EXPECT_EQ(u.status, FilterStatus::kRejected) << "rejection " << k;
    EXPECT_NEAR(u.nis, 30.0, 1e-12);
    EXPECT_EQ(u.dx, Eigen::Vector3d::Zero());
    EXPECT_EQ(P, p.P);  // untouched
    EXPECT_EQ(consecutive, k);
  }
  EXPECT_EQ(counts.rejected_updates, 2);
  // the third wild measurement in a row is fused anyway
  const auto forced =
      GatedKalmanUpdate<3, 2>(wild, p.H, p.R, gate, GainProduct::kHP, &consecutive, &P, &counts);
  EXPECT_EQ(forced.status, FilterStatus::kOk);
  EXPECT_TRUE(forced.forced);
  EXPECT_EQ(consecutive, 0);
  EXPECT_EQ(counts.forced_accepts, 1);
  EXPECT_EQ(counts.accepted_updates, 1);
  EXPECT_GT(forced.dx.head<2>().minCoeff(), 0.5);  // moved most of the way (P >> R)
  // an in-gate measurement is accepted normally and does not count as forced
  const auto normal =
      GatedKalmanUpdate<3, 2>(fair, p.H, p.R, gate, GainProduct::kHP, &consecutive, &P, &counts);
  EXPECT_EQ(normal.status, FilterStatus::kOk);
  EXPECT_FALSE(normal.forced);
  EXPECT_EQ(counts.forced_accepts, 1);
  EXPECT_EQ(counts.accepted_updates, 2);
}

TEST(GatedUpdateTest, SingularInnovationCovarianceIsRefused) {
  // P = 0 and an indefinite, singular R: LDLT meets a zero pivot with a non-zero column below it
  const Matrix3d P = Matrix3d::Zero();
  const Eigen::Matrix<double, 3, 3> H = Matrix3d::Identity();
  const Matrix3d R = (Matrix3d() << 1, 0, 0, 0, 0, 1, 0, 1, 0).finished();
  int consecutive = 0;
  FilterCounts counts;
  Matrix3d P_out = P;
  const auto u = GatedKalmanUpdate<3, 3>(Eigen::Vector3d(0.1, 0.1, 0.1), H, R, InnovationGate{},
                                         GainProduct::kHP, &consecutive, &P_out, &counts);
  EXPECT_EQ(u.status, FilterStatus::kNonFinite);
  EXPECT_EQ(counts.non_finite, 1);
  EXPECT_EQ(P_out, P);
}

TEST(GatedUpdateTest, NonFiniteInnovationCovarianceIsRefused) {
  const Problem p;
  Matrix2d R = p.R;
  R(0, 0) = std::nan("");
  int consecutive = 0;
  FilterCounts counts;
  Matrix3d P = p.P;
  const auto u = GatedKalmanUpdate<3, 2>(Eigen::Vector2d(0.1, 0.1), p.H, R, InnovationGate{},
                                         GainProduct::kHP, &consecutive, &P, &counts);
  EXPECT_EQ(u.status, FilterStatus::kNonFinite);
  EXPECT_EQ(counts.non_finite, 1);
  EXPECT_EQ(counts.accepted_updates, 0);
  EXPECT_EQ(P, p.P);
}

}  // namespace
}  // namespace hpa
