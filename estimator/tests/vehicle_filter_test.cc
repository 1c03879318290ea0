// VehicleFilter: a vehicle's own state from its IMU and VIO, never non-finite.

#include "hpa/estimator/vehicle_filter.h"

#include <gtest/gtest.h>

#include <cmath>

#include "hpa/models/params.h"

namespace hpa {
namespace {

constexpr double kGravity_mps2 = 9.81;

// A hovering vehicle's IMU sample at time_s: no rotation, specific force g up.
ImuSample HoverImu(double time_s) {
  ImuSample imu;
  imu.time_s = time_s;
  imu.accel_B_mps2 = Eigen::Vector3d(0, 0, kGravity_mps2);
  return imu;
}

QuadFilterState Start() {
  QuadFilterState s;
  s.p_WB_W = Eigen::Vector3d(1.0, -0.5, 2.0);
  return s;
}

TEST(VehicleFilter, HoverStaysWhereVioSaysAndMovesWithIt) {
  Params params;
  VehicleFilter filter(params, QuadFilterConfig(), Start());
  // 1 s of hover at 500 Hz with VIO at 30 Hz at a position 5 cm east of the start: the estimate
  // follows VIO (the filter's VIO noise is 1 cm, so it must end within a centimetre of it)
  const Eigen::Vector3d p_vio_W = Start().p_WB_W + Eigen::Vector3d(0.05, 0, 0);
  int next_vio = 0;
  for (int k = 1; k <= 500; ++k) {
    const double t = k * 0.002;
    filter.OnImu(HoverImu(t));
    if (t >= next_vio / 30.0) {
      VioSample vio;
      vio.time_s = t;
      vio.p_WB_W = p_vio_W;
      filter.OnVio(vio);
      ++next_vio;
    }
  }
  const QuadFilterState e = filter.Estimate(1.0, 0.05);
  EXPECT_LT((e.p_WB_W - p_vio_W).norm(), 0.01);
  EXPECT_LT(e.v_WB_W.norm(), 0.05);
  EXPECT_EQ(filter.restarts(), 0);
}

TEST(VehicleFilter, NonFiniteStateRestartsFromTheLastVio) {
  Params params;
  VehicleFilter filter(params, QuadFilterConfig(), Start());
  VioSample vio;
  vio.time_s = 0.002;
  vio.p_WB_W = Eigen::Vector3d(0.3, 0.2, 1.5);
  filter.OnImu(HoverImu(0.002));
  filter.OnVio(vio);
  // a finite but overflowing specific force makes the prediction infinite
  ImuSample wild = HoverImu(0.004);
  wild.accel_B_mps2 = Eigen::Vector3d(1e308, 1e308, 1e308);
  filter.OnImu(wild);
  EXPECT_EQ(filter.restarts(), 1);
  const QuadFilterState e = filter.Estimate(0.004, 0.05);
  EXPECT_TRUE(e.p_WB_W.allFinite() && e.v_WB_W.allFinite() && e.q_WB.coeffs().allFinite());
  EXPECT_NEAR((e.p_WB_W - vio.p_WB_W).norm(), 0.0, 1e-12);
}

TEST(VehicleFilter, WithoutVioANonFiniteFilterReportsTheStart) {
  Params params;
  VehicleFilter filter(params, QuadFilterConfig(), Start());
  filter.OnImu(HoverImu(0.002));
  ImuSample wild = HoverImu(0.004);
  wild.accel_B_mps2 = Eigen::Vector3d(1e308, 1e308, 1e308);
  filter.OnImu(wild);
  EXPECT_EQ(filter.restarts(), 0);  // nothing to restart from
  const QuadFilterState e = filter.Estimate(0.01, 0.05);
  EXPECT_TRUE(e.p_WB_W.allFinite());
  EXPECT_EQ(e.p_WB_W, Start().p_WB_W);
}

}  // namespace
}  // namespace hpa
