#include "hpa/estimator/quad_filter.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <deque>
#include <random>

#include "estimator/src/so3.h"

namespace hpa {
namespace {

// Known smooth truth: body rate and world acceleration are closed-form functions of time; the
// attitude and position are integrated with 10 substeps per IMU period (far finer than the filter).
struct TruthSim {
  double t_s = 0.0;
  Eigen::Vector3d p_W{0, 0, 1};
  Eigen::Vector3d v_W = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R_WB = Eigen::Matrix3d::Identity();
  Eigen::Vector3d gyro_bias{0.01, -0.02, 0.015};
  Eigen::Vector3d accel_bias{0.1, -0.05, 0.08};

  static Eigen::Vector3d Rate_B(double t) {
    return {0.6 * std::sin(1.1 * t), 0.5 * std::cos(0.7 * t), 0.3 * std::sin(0.5 * t)};
  }
  static Eigen::Vector3d Accel_W(double t) {
    return {1.5 * std::sin(0.8 * t), 1.2 * std::cos(0.6 * t), 0.8 * std::sin(1.3 * t)};
  }
  void Advance(double dt_s) {
    constexpr int kSub = 10;
    const double h = dt_s / kSub;
    for (int i = 0; i < kSub; ++i) {
      const double tm = t_s + 0.5 * h;
      R_WB = R_WB * ExpSo3(Rate_B(tm) * h);
      p_W += v_W * h + 0.5 * Accel_W(tm) * h * h;
      v_W += Accel_W(tm) * h;
      t_s += h;
    }
  }
  QuadFilterState State() const {
    QuadFilterState s;
    s.time_s = t_s;
    s.p_WB_W = p_W;
    s.v_WB_W = v_W;
    s.q_WB = Eigen::Quaterniond(R_WB);
    s.gyro_bias_B_radps = gyro_bias;
    s.accel_bias_B_mps2 = accel_bias;
    return s;
  }
};

struct RunResult {
  double mean_nees = 0.0;  // time-averaged NEES (15 dof) after convergence
  double position_rmse_m = 0.0;
  int rejected = 0;
};

// 20 s run: IMU at 500 Hz, VIO at 30 Hz delivered `latency_s` after capture. If
// `latency_aware` is false the VIO sample is re-stamped with its arrival time (the naive filter).
RunResult RunFilter(uint64_t seed, double latency_s, bool latency_aware) {
  const Params params;
  const QuadFilterConfig config;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  auto noise3 = [&](double std_dev) -> Eigen::Vector3d {
    return Eigen::Vector3d(n01(rng), n01(rng), n01(rng)) * std_dev;
  };

  TruthSim truth;
  QuadFilterState initial = truth.State();
  initial.gyro_bias_B_radps.setZero();  // the filter does not know the biases
  initial.accel_bias_B_mps2.setZero();
  initial.p_WB_W += noise3(config.initial_position_std_m);
  QuadFilter filter(params, config, initial);

  constexpr double kImuDt = 1.0 / 500.0;
  constexpr double kVioDt = 1.0 / 30.0;
  const double duration_s = 20.0;
  std::deque<VioSample> in_flight;
  double next_vio_s = kVioDt;
  RunResult result;
  double nees_sum = 0.0, se_sum = 0.0;
  int nees_count = 0;
  for (int k = 1; k * kImuDt <= duration_s + 1e-9; ++k) {
    truth.Advance(kImuDt);
    // bias random walk and IMU sample at the densities the filter assumes
    truth.gyro_bias += noise3(config.gyro_bias_walk_radps2_per_sqrthz * std::sqrt(kImuDt));
    truth.accel_bias += noise3(config.accel_bias_walk_mps3_per_sqrthz * std::sqrt(kImuDt));
    ImuSample imu;
    imu.time_s = truth.t_s;
    imu.gyro_B_radps = TruthSim::Rate_B(truth.t_s) + truth.gyro_bias +
                       noise3(config.gyro_noise_radps_per_sqrthz / std::sqrt(kImuDt));
    imu.accel_B_mps2 =
        truth.R_WB.transpose() * (TruthSim::Accel_W(truth.t_s) + Eigen::Vector3d(0, 0, 9.81)) +
        truth.accel_bias + noise3(config.accel_noise_mps2_per_sqrthz / std::sqrt(kImuDt));
    EXPECT_EQ(filter.Predict(imu), FilterStatus::kOk);

    // VIO capture and delayed delivery
    if (truth.t_s >= next_vio_s - 1e-9) {
      next_vio_s += kVioDt;
      VioSample vio;
      vio.time_s = truth.t_s;
      vio.p_WB_W = truth.p_W + noise3(config.vio_position_std_m);
      vio.q_WB = Eigen::Quaterniond(truth.R_WB * ExpSo3(noise3(config.vio_attitude_std_rad)));
      vio.v_WB_W = truth.v_W + noise3(config.vio_velocity_std_mps);
      in_flight.push_back(vio);
    }
    while (!in_flight.empty() && in_flight.front().time_s + latency_s <= truth.t_s + 1e-9) {
      VioSample vio = in_flight.front();
      in_flight.pop_front();
      if (!latency_aware) vio.time_s = truth.t_s;
      const FilterStatus status = filter.UpdateVio(vio);
      result.rejected += status == FilterStatus::kRejected;
    }

    // NEES after 2 s (initial bias transient) every 10 ms
    if (truth.t_s > 2.0 && k % 5 == 0) {
      const Vector15d e = QuadFilter::ErrorState(filter.state(), truth.State());
      nees_sum += e.dot(filter.covariance().ldlt().solve(e));
      se_sum += e.head<3>().squaredNorm();
      ++nees_count;
    }
  }
  result.mean_nees = nees_sum / nees_count;
  result.position_rmse_m = std::sqrt(se_sum / nees_count);
  return result;
}

TEST(QuadFilterTest, NeesStaysConsistentWithDelayedVio) {
  // 5 seeds x 20 s with 50 ms VIO latency. A consistent filter has E[NEES] = 15 (15 error
  // states); time-correlated samples make one run's mean wander, so the band is [7.5, 30]
  // (0.5x to 2x), the usual "sensible" band for a first-order EKF
  double nees_total = 0.0;
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    const RunResult r = RunFilter(seed, 0.05, true);
    std::printf("seed %lu: mean NEES %.2f, position RMSE %.2f mm, rejected %d\n",
                static_cast<unsigned long>(seed), r.mean_nees, 1e3 * r.position_rmse_m, r.rejected);
    EXPECT_GT(r.mean_nees, 7.5);
    EXPECT_LT(r.mean_nees, 30.0);
    EXPECT_EQ(r.rejected, 0);
    nees_total += r.mean_nees;
  }
  std::printf("mean NEES over 5 runs: %.2f (15 expected)\n", nees_total / 5);
}

TEST(QuadFilterTest, LatencyAwareUpdateBeatsNaiveRestamping) {
  // 100 ms latency with fast motion: applying the sample at arrival time is wrong by v * 0.1 s
  const RunResult aware = RunFilter(11, 0.1, true);
  const RunResult naive = RunFilter(11, 0.1, false);
  std::printf("100 ms latency: position RMSE aware %.2f mm, naive %.2f mm\n",
              1e3 * aware.position_rmse_m, 1e3 * naive.position_rmse_m);
  EXPECT_LT(aware.position_rmse_m, 0.5 * naive.position_rmse_m);
  // VIO noise is 10 mm per axis; fusion with the IMU must stay below it
  EXPECT_LT(aware.position_rmse_m, 0.01 * std::sqrt(3.0));
}

TEST(QuadFilterTest, NonFiniteAndStaleInputsAreRejected) {
  const Params params;
  QuadFilter filter(params, QuadFilterConfig{}, QuadFilterState{});
  ImuSample imu;
  imu.time_s = 0.002;
  imu.accel_B_mps2 = Eigen::Vector3d(0, 0, 9.81);
  EXPECT_EQ(filter.Predict(imu), FilterStatus::kOk);
  ImuSample bad = imu;
  bad.time_s = 0.004;
  bad.gyro_B_radps.x() = std::nan("");
  EXPECT_EQ(filter.Predict(bad), FilterStatus::kNonFinite);
  EXPECT_EQ(filter.Predict(imu), FilterStatus::kOutOfOrder);
  VioSample vio;
  vio.time_s = -1.0;  // older than the 0.5 s history
  EXPECT_EQ(filter.UpdateVio(vio), FilterStatus::kTooOld);
  vio.time_s = 0.002;
  vio.p_WB_W.x() = INFINITY;
  EXPECT_EQ(filter.UpdateVio(vio), FilterStatus::kNonFinite);
  vio.p_WB_W.x() = 0.0;
  vio.q_WB.coeffs().setZero();  // no attitude
  EXPECT_EQ(filter.UpdateVio(vio), FilterStatus::kNonFinite);
  EXPECT_TRUE(filter.state().p_WB_W.allFinite());
  EXPECT_EQ(filter.state().time_s, 0.002);
  EXPECT_EQ(filter.counts().non_finite, 3);
  EXPECT_EQ(filter.counts().out_of_order, 1);
  EXPECT_EQ(filter.counts().too_old, 1);
  EXPECT_EQ(filter.counts().accepted_updates, 0);
}

TEST(QuadFilterTest, WildVioIsRejectedUntilTheRunForcesAnAccept) {
  // at rest; VIO then reports the vehicle 1 m to the side (a relocalisation jump)
  const Params params;
  const QuadFilterConfig config;
  QuadFilterState initial;
  initial.p_WB_W = Eigen::Vector3d(0, 0, 1);
  QuadFilter filter(params, config, initial);
  ImuSample imu;
  imu.accel_B_mps2 = Eigen::Vector3d(0, 0, params.gravity_mps2);
  int k = 0;
  auto step = [&]() {
    imu.time_s = ++k / 500.0;
    ASSERT_EQ(filter.Predict(imu), FilterStatus::kOk);
  };
  VioSample vio;
  vio.p_WB_W = initial.p_WB_W;
  for (int i = 0; i < 17; ++i) step();
  vio.time_s = imu.time_s;
  EXPECT_EQ(filter.UpdateVio(vio), FilterStatus::kOk);
  EXPECT_LT(filter.counts().last_nis, config.vio_gate.nis_threshold);
  vio.p_WB_W.x() += 1.0;
  for (int n = 1; n <= config.vio_gate.max_consecutive_rejections; ++n) {
    for (int i = 0; i < 17; ++i) step();
    vio.time_s = imu.time_s;
    EXPECT_EQ(filter.UpdateVio(vio), FilterStatus::kRejected) << "sample " << n;
    EXPECT_GT(filter.counts().last_nis, config.vio_gate.nis_threshold);
    EXPECT_LT(std::abs(filter.state().p_WB_W.x()), 1e-9);  // rejected: untouched
  }
  EXPECT_EQ(filter.counts().rejected_updates, config.vio_gate.max_consecutive_rejections);
  // the next one in the run is fused (the filter, not VIO, is assumed off), also when late
  for (int i = 0; i < 17; ++i) step();
  vio.time_s = imu.time_s - 0.01;
  EXPECT_EQ(filter.UpdateVio(vio), FilterStatus::kOk);
  EXPECT_EQ(filter.counts().forced_accepts, 1);
  EXPECT_EQ(filter.counts().accepted_updates, 2);
  // pulled toward the jump: measured 0.46 m (P and R comparable), bound 0.3 m
  EXPECT_GT(filter.state().p_WB_W.x(), 0.3);
}

TEST(QuadFilterTest, HoverAtRestStaysPut) {
  // level, at rest: the IMU reads +g along body z; with no noise the state must not drift
  const Params params;
  QuadFilterState initial;
  initial.p_WB_W = Eigen::Vector3d(0.3, -0.2, 1.0);
  QuadFilter filter(params, QuadFilterConfig{}, initial);
  for (int k = 1; k <= 1000; ++k) {
    ImuSample imu;
    imu.time_s = k / 500.0;
    imu.accel_B_mps2 = Eigen::Vector3d(0, 0, params.gravity_mps2);
    ASSERT_EQ(filter.Predict(imu), FilterStatus::kOk);
  }
  // exact arithmetic gives zero drift; 1e-9 m covers rounding over 1000 steps
  EXPECT_LT((filter.state().p_WB_W - initial.p_WB_W).norm(), 1e-9);
  EXPECT_NEAR(filter.state().time_s, 2.0, 1e-12);
}

}  // namespace
}  // namespace hpa
