// hpa::sim::TeamWorld's per-vehicle components: each vehicle's onboard sensors (the single
// vehicle's IMU and VIO at their rates, the specific force at hover, its own faults, its own
// noise, replayed by the same seed and by a Reset) and the world's disturbances on a vehicle (an
// impulse spread over its duration, the single quadrotor's drag on each vehicle).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <type_traits>
#include <variant>
#include <vector>

#include "hpa/models/cooperative_model.h"
#include "hpa/sim/faults.h"
#include "hpa/sim/team_world.h"
#include "sim/tests/test_teams.h"

namespace hpa::sim {
namespace {

using Eigen::Vector3d;
using Eigen::VectorXd;
using I = CooperativeStateIndex;

TeamWorldConfig OnboardConfig(uint64_t seed = 1) {
  TeamWorldConfig c;
  c.team = TestBar();
  c.seed = seed;
  c.onboard_sensors = true;
  return c;
}

// Every number of a message, its kind first: two runs' messages compare bit for bit.
std::vector<double> Numbers(const SensorMessage& message) {
  std::vector<double> out;
  std::visit(
      [&out](const auto& m) {
        using T = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<T, ImuSample>) {
          out = {1,
                 m.time_s,
                 m.gyro_B_radps.x(),
                 m.gyro_B_radps.y(),
                 m.gyro_B_radps.z(),
                 m.accel_B_mps2.x(),
                 m.accel_B_mps2.y(),
                 m.accel_B_mps2.z()};
        } else if constexpr (std::is_same_v<T, VioSample>) {
          out = {2,          m.time_s,   m.p_WB_W.x(), m.p_WB_W.y(), m.p_WB_W.z(), m.q_WB.w(),
                 m.q_WB.x(), m.q_WB.y(), m.q_WB.z(),   m.v_WB_W.x(), m.v_WB_W.y(), m.v_WB_W.z()};
        } else if constexpr (std::is_same_v<T, GyroSample>) {
          out = {3, m.time_s, m.gyro_B_radps.x(), m.gyro_B_radps.y(), m.gyro_B_radps.z()};
        } else {
          out = {4, Sensor::CaptureTime(m)};
        }
      },
      message);
  return out;
}

// Each vehicle's delivered messages over `steps` steps, flattened (vehicle x message).
std::vector<std::vector<std::vector<double>>> Delivered(TeamWorld* world, int steps) {
  std::vector<std::vector<std::vector<double>>> out(world->VehicleCount());
  std::vector<SensorMessage> delivered;
  for (int s = 0; s < steps; ++s) {
    world->Step();
    for (int v = 0; v < world->VehicleCount(); ++v) {
      world->TakeDelivered(v, &delivered);
      for (const SensorMessage& m : delivered) out[v].push_back(Numbers(m));
    }
  }
  return out;
}

// (a) Each vehicle of a hovering two-vehicle team receives its IMU at the IMU's rate and its VIO
// at the VIO's rate. Vehicle 1's specific force at hover is g along its body z: the hover holds
// (the vehicles' accelerations after the cables' first settling are far below the noise), so
// what is left is the IMU's white noise, per sample density / sqrt(period) = 1.7e-3 / sqrt(2 ms)
// = 0.038 m/s^2 per axis; a sample lies within 6 sigma of g (one sample in 5e8 outside), and
// the mean of the N samples within 6 sigma / sqrt(N) plus the bias walk's 3e-4 m/s^3/sqrt(Hz)
// over the run (under 1e-3 m/s^2 at 6 sigma).
TEST(TeamOnboardTest, EachVehicleReceivesItsImuAndVioAtTheirRates) {
  TeamWorld world(OnboardConfig());
  world.Reset(CooperativeModel(TestBar()).HangingState(Vector3d(0, 0, 1.5)));
  ASSERT_TRUE(world.onboard_sensors());
  ASSERT_EQ(world.sensors(0).size(), 2u);  // IMU and VIO: the ideal profile has no rate gyro
  EXPECT_EQ(world.sensors(1)[0]->declaration().name, "imu");
  EXPECT_EQ(world.sensors(1)[1]->declaration().name, "vio");
  EXPECT_THROW(world.sensors(2), std::out_of_range);
  std::vector<SensorMessage> out;
  EXPECT_THROW(world.TakeDelivered(-1, &out), std::out_of_range);

  const RateTable rates;
  const SensorNoiseConfig noise;
  const double g_mps2 = TestBar().gravity_mps2;
  const double sigma_mps2 = noise.accel_noise_density_mps2_rthz * std::sqrt(rates.imu.rate_hz);
  const int steps = 2000;  // 2 s
  int imu[2] = {0, 0}, vio[2] = {0, 0};
  double sum_fz_mps2 = 0.0, max_dev_mps2 = 0.0;
  int settled = 0;
  for (int s = 0; s < steps; ++s) {
    world.Step();
    for (int v = 0; v < 2; ++v) {
      world.TakeDelivered(v, &out);
      for (const SensorMessage& m : out) {
        if (const auto* sample = std::get_if<ImuSample>(&m)) {
          ++imu[v];
          if (v == 1 && sample->time_s >= 0.5) {  // after the cables' first settling
            const Vector3d dev = sample->accel_B_mps2 - Vector3d(0, 0, g_mps2);
            max_dev_mps2 = std::max(max_dev_mps2, dev.cwiseAbs().maxCoeff());
            sum_fz_mps2 += sample->accel_B_mps2.z();
            ++settled;
          }
        }
        if (std::holds_alternative<VioSample>(m)) ++vio[v];
      }
    }
  }
  const double mean_fz_mps2 = sum_fz_mps2 / settled;
  std::printf(
      "[measured] IMU %d, %d; VIO %d, %d; vehicle 1 |f - g e3| max %.4f m/s^2 (sigma "
      "%.4f), mean f_z - g %.2e m/s^2\n",
      imu[0], imu[1], vio[0], vio[1], max_dev_mps2, sigma_mps2, mean_fz_mps2 - g_mps2);
  for (int v = 0; v < 2; ++v) {
    // one per period over 2 s, the last VIO sample still within its 20 ms latency
    EXPECT_NEAR(imu[v], 2.0 * rates.imu.rate_hz, 1);
    EXPECT_NEAR(vio[v], 2.0 * rates.vio.rate_hz, 1);
  }
  EXPECT_LT(max_dev_mps2, 6 * sigma_mps2);
  EXPECT_NEAR(mean_fz_mps2, g_mps2, 6 * sigma_mps2 / std::sqrt(settled) + 1e-3);
}

// (a) A VIO fault injected into vehicle 0's faults removes vehicle 0's VIO messages in its
// window and leaves vehicle 1's and every IMU message.
TEST(TeamOnboardTest, AVioFaultOnOneVehicleLeavesTheOther) {
  TeamWorld world(OnboardConfig());
  world.Reset(CooperativeModel(TestBar()).HangingState(Vector3d(0, 0, 1.5)));
  Fault off;
  off.component = FaultComponent::kVio;
  off.mode = FaultMode::kOff;
  off.start_s = 0.0;
  off.end_s = 10.0;
  world.faults(0).Inject(off);
  int imu[2] = {0, 0}, vio[2] = {0, 0};
  std::vector<SensorMessage> out;
  for (int s = 0; s < 1000; ++s) {
    world.Step();
    for (int v = 0; v < 2; ++v) {
      world.TakeDelivered(v, &out);
      for (const SensorMessage& m : out) {
        imu[v] += std::holds_alternative<ImuSample>(m) ? 1 : 0;
        vio[v] += std::holds_alternative<VioSample>(m) ? 1 : 0;
      }
    }
  }
  EXPECT_EQ(vio[0], 0);
  EXPECT_NEAR(vio[1], 30, 1);
  EXPECT_EQ(imu[0], imu[1]);
  EXPECT_NEAR(imu[0], 500, 1);
}

// (b) The same seed gives the same messages bit for bit, a Reset world replays them, another
// seed draws other noise, the two vehicles' noises differ, and the motion capture is the same
// with and without onboard sensors (their generators are their own).
TEST(TeamOnboardTest, SameSeedSameMessagesAndAResetReplaysThem) {
  const VectorXd x0 = CooperativeModel(TestBar()).HangingState(Vector3d(0, 0, 1.5));
  TeamWorld a(OnboardConfig(7)), b(OnboardConfig(7)), other(OnboardConfig(8));
  a.Reset(x0);
  b.Reset(x0);
  other.Reset(x0);
  const auto first = Delivered(&a, 500);
  EXPECT_EQ(first, Delivered(&b, 500));
  EXPECT_NE(first, Delivered(&other, 500));
  ASSERT_GT(first[0].size(), 200u);
  EXPECT_NE(first[0], first[1]);
  a.Reset(x0);
  EXPECT_EQ(first, Delivered(&a, 500));

  TeamWorldConfig without = OnboardConfig(7);
  without.onboard_sensors = false;
  TeamWorld plain(without);
  plain.Reset(x0);
  a.Reset(x0);
  EXPECT_TRUE(plain.sensors(1).empty());
  std::vector<SensorMessage> none;
  for (int s = 0; s < 300; ++s) {
    plain.Step();
    a.Step();
    plain.TakeDelivered(1, &none);
    EXPECT_TRUE(none.empty());
    const std::vector<BodyReading> r_plain = plain.TakeDelivered(), r_onboard = a.TakeDelivered();
    ASSERT_EQ(r_plain.size(), r_onboard.size());
    for (size_t k = 0; k < r_plain.size(); ++k) {
      EXPECT_EQ(r_plain[k].p_W_m, r_onboard[k].p_W_m);
      EXPECT_EQ(r_plain[k].v_W_mps, r_onboard[k].v_W_mps);
    }
    EXPECT_EQ(plain.GyroSample_B(0), a.GyroSample_B(0));
  }
}

// (c) An impulse on a vehicle over 50 ms changes its momentum by the impulse, step by step over
// the whole duration, and stops with it. A sideways J = m_Q x 0.2 m/s on vehicle 1 of the
// hanging bar: what else changes its horizontal momentum over the 50 ms is its cable's pull
// across the push (the vehicle moves a few mm against a 0.6 m cable) and its thrust tilting;
// measured about 0.1 % of J, the bound is 1 %. Every step adds J / (m_Q 50) but for that (half
// of it is the bound), and the step after the duration adds under a tenth of it.
TEST(TeamOnboardTest, AnImpulseOnAVehicleLastsItsDurationAndGivesItsMomentum) {
  TeamWorldConfig config = OnboardConfig();
  config.onboard_sensors = false;
  TeamWorld world(config);
  world.Reset(CooperativeModel(TestBar()).HangingState(Vector3d(0, 0, 1.5)));
  for (int s = 0; s < 100; ++s) world.Step();
  const double m_kg = TestBar().vehicles[1].params.quad_mass_kg;
  const double dv_mps = 0.2;
  const int vx = I::Vehicle(1) + 3;  // vehicle 1's x velocity
  const double v0_mps = world.GetTruth().x(vx);
  world.ApplyImpulse(1, Vector3d(m_kg * dv_mps, 0, 0), 0.05);
  double last_mps = v0_mps;
  for (int s = 0; s < 50; ++s) {
    world.Step();
    const double v_mps = world.GetTruth().x(vx);
    EXPECT_GT(v_mps - last_mps, 0.5 * dv_mps / 50) << "step " << s;  // pushed on every step
    last_mps = v_mps;
  }
  std::printf("[measured] impulse on vehicle 1: dv %.5f m/s of %.5f\n", last_mps - v0_mps, dv_mps);
  EXPECT_NEAR(last_mps - v0_mps, dv_mps, 0.01 * dv_mps);
  world.Step();
  EXPECT_LT(std::abs(world.GetTruth().x(vx) - last_mps), 0.1 * dv_mps / 50);  // over
  // the payload and the other vehicle were not pushed directly: the payload barely moved
  EXPECT_LT(std::abs(world.GetTruth().x(I::kPayloadVel)), 0.1 * dv_mps);
  EXPECT_THROW(world.disturbances().ApplyImpulse(BodyRef(2), Vector3d::Zero()), std::out_of_range);
}

// With the profile's air, each vehicle feels the single quadrotor's drag from its own params'
// box (the closed form of Disturbances: 0.5 rho Cd A v^2 over the face the air meets), the
// payload a sphere's; without it, none.
TEST(TeamOnboardTest, EachVehicleFeelsTheSingleQuadrotorsDrag) {
  TeamWorldConfig config = OnboardConfig();
  config.onboard_sensors = false;
  config.profile.aero.enabled = true;
  config.profile.aero.body_drag_coefficient_xy = 1.05;
  config.profile.aero.payload_drag_coefficient = 0.47;
  TeamWorld world(config);
  world.Reset(CooperativeModel(TestBar()).HangingState(Vector3d(0, 0, 1.5)));
  world.AddVelocity(1, Vector3d(3.0, 0, 0));
  const VectorXd x = world.GetTruth().x;
  world.Step();
  const Vector3d v_W = x.segment<3>(I::Vehicle(1) + 3);
  const Vector3d h = TestBar().vehicles[1].params.body_half_size_m;
  const double expected_N = 0.5 * 1.225 * 1.05 * (4 * h.y() * h.z()) * v_W.norm() * v_W.x();
  // the hanging vehicle is level to rounding: its drag is the closed form's to 1e-9 N
  EXPECT_NEAR(world.disturbances().aero_vehicle_W_N(1).x(), -expected_N, 1e-9);
  EXPECT_LT(world.disturbances().aero_vehicle_W_N(0).norm(), 1e-6);
  EXPECT_LT(world.disturbances().aero_payload_W_N().norm(), 1e-6);
}

}  // namespace
}  // namespace hpa::sim
