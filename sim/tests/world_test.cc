// hpa::sim::World: loading errors, hover, motors, sensors (rates, noise, determinism),
// disturbances, gripper, crash detection and world overrides.
#include "hpa/sim/world.h"
#include "sim/tests/default_world_config.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/models/rotor_model.h"
#include "models/tests/temp_dir.h"
#include "sim/src/world_internals.h"

namespace hpa::sim {
namespace {

// The messages of type T among `messages` (what World::TakeDelivered returned), in order.
template <class T>
std::vector<T> OfType(const std::vector<SensorMessage>& messages) {
  std::vector<T> out;
  for (const SensorMessage& m : messages) {
    if (const T* t = std::get_if<T>(&m)) out.push_back(*t);
  }
  return out;
}


InputVector HoverCommand(const World& world) {
  return InputVector::Constant(world.world_params().HoverMotorSpeedRadps());
}

TEST(WorldTest, MissingSceneIsAnInputErrorNamingTheFile) {
  WorldConfig c = DefaultConfig();
  c.scene_path = "/nonexistent/scene.xml";
  try {
    World world(c);
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scene.xml"), std::string::npos);
  }
}

TEST(WorldTest, MalformedSceneIsAnInputErrorNamingTheFile) {
  const std::string path = TestTempDir() + "bad_scene.xml";
  std::ofstream(path) << "<mujoco><worldbody><body name='quadrotor'><geom type='box'/>";
  WorldConfig c = DefaultConfig();
  c.scene_path = path;
  try {
    World world(c);
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(WorldTest, SceneWithoutTheCableIsAnInputError) {
  const std::string path = TestTempDir() + "no_cable.xml";
  std::ofstream(path) << "<mujoco><option timestep='0.001'/><worldbody>"
                         "<body name='quadrotor'><freejoint name='quadrotor_joint'/>"
                         "<geom type='box' size='.1 .1 .03'/></body></worldbody></mujoco>";
  WorldConfig c = DefaultConfig();
  c.scene_path = path;
  EXPECT_THROW(World world(c), InputError);
}

TEST(WorldTest, HoversInPlaceWithPayloadHanging) {
  World world(DefaultConfig());
  world.SetMotorSpeedCommand(HoverCommand(world));
  for (int k = 0; k < 2000; ++k) world.Step();
  const Truth t = world.GetTruth();
  EXPECT_NEAR(world.time_s(), 2.0, 1e-12);
  // exact hover thrust: any drift comes from the cable's 0.04 mm stretch settling; 1 mm in 2 s
  EXPECT_LT((t.state.p_WQ_W - Eigen::Vector3d(0, 0, 1)).norm(), 1e-3);
  EXPECT_LT(t.state.v_WQ_W.norm(), 1e-3);
  EXPECT_EQ(t.state.mode, CableMode::kTaut);
  EXPECT_FALSE(world.Crash().crashed);
  EXPECT_TRUE(t.state.AllFinite());
}

TEST(WorldTest, MotorsFollowTheCommandWithFirstOrderLag) {
  World world(DefaultConfig());
  const Params& p = world.world_params();
  const double w0 = p.HoverMotorSpeedRadps();
  const double w1 = w0 + 200.0;
  world.SetMotorSpeedCommand(InputVector::Constant(w1));
  const int steps = static_cast<int>(std::lround(p.motor_time_constant_s / World::kPhysicsDt_s));
  for (int k = 0; k < steps; ++k) world.Step();
  // after one time constant: 1 - e^-1 of the step (exact discretisation, so 1e-9)
  const double expected = w0 + (1.0 - std::exp(-1.0)) * (w1 - w0);
  EXPECT_NEAR(world.GetTruth().motor_speed_radps(0), expected, 1e-9);
  // commands are clamped to the motor bounds
  world.SetMotorSpeedCommand(InputVector::Constant(1e6));
  for (int k = 0; k < 1000; ++k) world.Step();
  EXPECT_LE(world.GetTruth().motor_speed_radps.maxCoeff(), p.motor_speed_max_radps);
  EXPECT_THROW(world.SetMotorSpeedCommand(InputVector::Constant(NAN)), std::invalid_argument);
}

TEST(WorldTest, ImuAt500HzVioAt30HzWithLatency) {
  World world(DefaultConfig());
  world.SetMotorSpeedCommand(HoverCommand(world));
  int n_imu = 0, n_vio = 0;
  double last_imu_t = -1;
  Eigen::Vector3d accel_sum = Eigen::Vector3d::Zero();
  for (int k = 0; k < 1000; ++k) {
    world.Step();
    const std::vector<SensorMessage> delivered = world.TakeDelivered();
    for (const ImuSample& s : OfType<ImuSample>(delivered)) {
      const ImuSample* imu = &s;
      if (last_imu_t >= 0) {
        EXPECT_NEAR(imu->time_s - last_imu_t, 0.002, 1e-12);
      }
      last_imu_t = imu->time_s;
      accel_sum += imu->accel_B_mps2;
      ++n_imu;
    }
    for (const VioSample& s : OfType<VioSample>(delivered)) {
      const VioSample* vio = &s;
      // delivered no earlier than capture + latency and within one step after it
      const double age_s = world.time_s() - vio->time_s;
      EXPECT_GE(age_s, DefaultConfig().rates.vio.latency_s - 1e-9);
      EXPECT_LT(age_s, DefaultConfig().rates.vio.latency_s + World::kPhysicsDt_s + 1e-9);
      EXPECT_LT((vio->p_WB_W - Eigen::Vector3d(0, 0, 1)).norm(), 0.1);  // 10 sigma
      ++n_vio;
    }
  }
  EXPECT_EQ(n_imu, 500);
  EXPECT_GE(n_vio, 29);  // 30 captures in 1 s, the last ones still in flight
  EXPECT_LE(n_vio, 30);
  // hovering: specific force = g up. Mean of 500 samples: noise 1.7e-3/sqrt(0.002)/sqrt(500)
  // = 1.7e-3 m/s^2 and bias walk < 1e-3 m/s^2 -> 0.02 m/s^2 is > 10 sigma
  const Eigen::Vector3d mean = accel_sum / n_imu;
  EXPECT_NEAR(mean.z(), 9.81, 0.02);
  EXPECT_NEAR(mean.x(), 0.0, 0.02);
}

TEST(WorldTest, SameSeedSameSamplesOtherSeedOtherSamples) {
  auto first_samples = [](uint64_t seed) {
    WorldConfig c = DefaultConfig();
    c.seed = seed;
    World world(c);
    std::vector<double> v;
    for (int k = 0; k < 100; ++k) {
      world.Step();
      const std::vector<SensorMessage> delivered = world.TakeDelivered();
      for (const ImuSample& imu : OfType<ImuSample>(delivered)) v.push_back(imu.gyro_B_radps.x());
      for (const VioSample& vio : OfType<VioSample>(delivered)) v.push_back(vio.p_WB_W.x());
    }
    return v;
  };
  EXPECT_EQ(first_samples(3), first_samples(3));
  EXPECT_NE(first_samples(3), first_samples(4));
}

TEST(WorldTest, ImpulseOnThePayloadChangesItsMomentum) {
  World world(DefaultConfig());
  // quadrotor holding itself, payload slack 0.3 m below: only gravity and the impulse act on it
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0, 0, 2);
  s.p_WL_W = Eigen::Vector3d(0, 0, 1.7);
  const Params& p = world.world_params();
  world.SetState(s.ToVector(), InputVector::Constant(std::sqrt(p.quad_mass_kg * p.gravity_mps2 /
                                                               (4 * p.k_f_N_per_radps2))));
  const Eigen::Vector3d impulse_Ns(0.02, -0.01, 0.03);
  world.disturbances().ApplyImpulse(Body::kPayload, impulse_Ns, 0.01);
  for (int k = 0; k < 20; ++k) world.Step();
  const Eigen::Vector3d expected_v =
      impulse_Ns / p.payload_mass_kg + Eigen::Vector3d(0, 0, -p.gravity_mps2 * 0.02);
  // semi-implicit Euler integrates constant forces exactly in velocity: 1e-9
  EXPECT_LT((world.GetTruth().state.v_WL_W - expected_v).norm(), 1e-9);
  EXPECT_EQ(world.GetTruth().state.mode, CableMode::kSlack);
}

TEST(WorldTest, WindPushesTheWholeSystem) {
  World world(DefaultConfig());
  const Params& p = world.world_params();
  world.SetMotorSpeedCommand(HoverCommand(world));
  const Eigen::Vector3d force_N(0.3, 0, 0);
  world.disturbances().SetWind(force_N, 0.2);
  for (int k = 0; k < 300; ++k) world.Step();
  const Truth t = world.GetTruth();
  const Eigen::Vector3d momentum =
      p.quad_mass_kg * t.state.v_WQ_W + p.payload_mass_kg * t.state.v_WL_W;
  // the wind's impulse 0.06 N s; thrust tilts by < 1e-3 rad meanwhile (the payload swings the
  // quad a little), so 1 % of it
  EXPECT_NEAR(momentum.x(), 0.06, 6e-4);
}

TEST(WorldTest, GripperHoldsMovesAndReleasesThePayload) {
  World world(DefaultConfig());
  world.SetMotorSpeedCommand(HoverCommand(world));
  const Eigen::Vector3d p0 = world.GetTruth().state.p_WL_W;
  world.gripper().Grab();
  EXPECT_TRUE(world.gripper().active());
  // the quadrotor now carries itself only (the gripper carries the payload)
  const Params& p = world.world_params();
  world.SetMotorSpeedCommand(
      InputVector::Constant(std::sqrt(p.quad_mass_kg * p.gravity_mps2 / (4 * p.k_f_N_per_radps2))));
  for (int k = 0; k < 100; ++k) world.Step();
  // held where it was grabbed (weld is soft: 2 mm)
  EXPECT_LT((world.GetTruth().state.p_WL_W - p0).norm(), 2e-3);
  const Eigen::Vector3d target = p0 + Eigen::Vector3d(0.1, 0, 0.2);
  world.gripper().Move(target, 0.5);
  for (int k = 0; k < 800; ++k) world.Step();
  const Truth held = world.GetTruth();
  EXPECT_LT((held.state.p_WL_W - target).norm(), 5e-3);
  EXPECT_EQ(held.state.mode, CableMode::kSlack);  // pushed 0.2 m up: cable slack
  world.gripper().Release();
  EXPECT_FALSE(world.gripper().active());
  for (int k = 0; k < 100; ++k) world.Step();
  EXPECT_LT(world.GetTruth().state.v_WL_W.z(), -0.5);  // falling after release
}

TEST(WorldTest, CrashOnGroundContact) {
  World world(DefaultConfig());
  world.SetMotorSpeedCommand(InputVector::Zero());  // clamped to idle: it falls
  for (int k = 0; k < 1500 && !world.Crash().crashed; ++k) world.Step();
  const CrashStatus c = world.Crash();
  ASSERT_TRUE(c.crashed);
  EXPECT_NE(c.reason.find("ground"), std::string::npos) << c.reason;
  // 1 m free fall (a bit less: body half-height 3 cm) takes sqrt(2 * 0.97 / 9.81) = 0.44 s
  EXPECT_NEAR(c.time_s, 0.44, 0.03);
  world.Step();
  EXPECT_EQ(world.Crash().time_s, c.time_s) << "latched";
}

TEST(WorldTest, CrashOnTiltAndArenaExit) {
  World world(DefaultConfig());
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0, 0, 3);
  s.p_WL_W = Eigen::Vector3d(0, 0, 2.5);
  s.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(1.7, Eigen::Vector3d::UnitX()));
  world.Reset(s);
  world.Step();
  EXPECT_EQ(world.Crash().reason, "tilt > 90 deg");

  s.q_WB = Eigen::Quaterniond::Identity();
  s.p_WQ_W = Eigen::Vector3d(9.999, 0, 3);
  s.p_WL_W = Eigen::Vector3d(9.999, 0, 2.5);
  s.v_WQ_W = s.v_WL_W = Eigen::Vector3d(5, 0, 0);
  world.Reset(s);
  EXPECT_FALSE(world.Crash().crashed) << "Reset clears the crash";
  for (int k = 0; k < 10; ++k) world.Step();
  EXPECT_NE(world.Crash().reason.find("arena"), std::string::npos);
}

TEST(WorldTest, OverridesChangeTheWorldOnly) {
  WorldConfig c = DefaultConfig();
  c.overrides.payload_mass_kg = 0.15;
  c.overrides.cable_length_m = 0.6;
  World world(c);
  EXPECT_DOUBLE_EQ(world.world_params().payload_mass_kg, 0.15);
  EXPECT_DOUBLE_EQ(c.params.payload_mass_kg, 0.1);
  world.SetMotorSpeedCommand(HoverCommand(world));
  for (int k = 0; k < 500; ++k) world.Step();
  const Truth t = world.GetTruth();
  // hanging tension = the heavier payload's weight; 1e-3 N as in the cable test
  EXPECT_NEAR(t.cable_tension_N, 0.15 * 9.81, 1e-3);
  EXPECT_NEAR(t.cable_length_m, 0.6, 1e-3);  // stretch 0.04 mm (cable test)
  EXPECT_EQ(t.state.mode, CableMode::kTaut);
  // inertia scaled with the mass: 2/5 m r^2
  const int payload = mj_name2id(WorldInternals::Model(world), mjOBJ_BODY, "payload");
  EXPECT_NEAR(WorldInternals::Model(world)->body_inertia[3 * payload], 0.4 * 0.15 * 0.04 * 0.04,
              1e-12);
}

}  // namespace
}  // namespace hpa::sim

namespace hpa::sim {
namespace {

// A params file other than the default must reach the world, not only the flight code: rotor
// arms, yaw gear, payload radius and the camera all follow WorldConfig::params.
TEST(WorldParamsTest, NonDefaultParamsReachTheModel) {
  WorldConfig c;
  c.params = LoadParams(DefaultParamsPath());
  c.params.arm_length_m = 0.2;
  c.params.k_m_Nm_per_radps2 = 3e-8;
  c.params.payload_radius_m = 0.05;
  c.params.camera_fovy_deg = 60.0;
  c.params.t_BC_B_m = Eigen::Vector3d(0.01, 0.0, -0.04);
  World world(c);
  const mjModel* m = WorldInternals::Model(world);
  const int act = mj_name2id(m, mjOBJ_ACTUATOR, "rotor0");
  const int site = m->actuator_trnid[2 * act];
  const Eigen::Vector3d r = RotorPosition_B(c.params, 0);
  for (int k = 0; k < 3; ++k) EXPECT_DOUBLE_EQ(m->site_pos[3 * site + k], r(k));
  EXPECT_DOUBLE_EQ(m->actuator_gear[6 * act + 5], RotorSpin(0) * 3e-8 / 1.5e-6);
  EXPECT_DOUBLE_EQ(m->geom_size[3 * mj_name2id(m, mjOBJ_GEOM, "payload_sphere")], 0.05);
  const int cam = mj_name2id(m, mjOBJ_CAMERA, "payload_camera");
  EXPECT_DOUBLE_EQ(m->cam_fovy[cam], 60.0);
  EXPECT_DOUBLE_EQ(m->cam_pos[3 * cam], 0.01);
  // the default R_BC is the scene's camera orientation: identity quaternion (looks along -z_B)
  EXPECT_NEAR(std::abs(m->cam_quat[4 * cam]), 1.0, 1e-12);
}

TEST(WorldTest, RateGyroSamplesAtTheRateLoopsRateOnlyWhenPx4Flies) {
  // off (the default profile): never a sample
  World off(DefaultConfig());
  off.Step();
  EXPECT_TRUE(OfType<GyroSample>(off.TakeDelivered()).empty());

  WorldConfig c = DefaultConfig();
  c.profile.rate_gyro.enabled = true;
  c.profile.rate_gyro.rate_hz = 1000.0;
  World world(c);
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0, 0, 1.0);
  s.p_WL_W = Eigen::Vector3d(0, 0, 0.5);
  s.w_B = Eigen::Vector3d(0.3, -0.2, 0.1);
  world.Reset(s);
  // one sample per 1 ms step, the newest only; its error is the noise plus the IMU's bias
  const SensorNoiseConfig noise;
  const double sigma = noise.gyro_noise_density_radps_rthz * std::sqrt(1000.0);
  double sum_sq = 0.0;
  int n = 0;
  for (int k = 0; k < 2000; ++k) {
    const Eigen::Vector3d w_true = world.GetTruth().state.w_B;
    world.Step();
    const std::vector<GyroSample> gyro = OfType<GyroSample>(world.TakeDelivered());
    ASSERT_EQ(gyro.size(), 1u);
    const GyroSample* g = &gyro.front();
    EXPECT_NEAR(g->time_s, k * World::kPhysicsDt_s, 1e-12);
    EXPECT_TRUE(OfType<GyroSample>(world.TakeDelivered()).empty());
    sum_sq += (g->gyro_B_radps - w_true).squaredNorm();
    n += 3;
  }
  // rms error: the white noise (the bias walks far less in 2 s); 6000 draws put the sample std
  // within 3 % of sigma at 3-sigma (1 / sqrt(2 n)), 10 % allowed for the bias
  EXPECT_NEAR(std::sqrt(sum_sq / n), sigma, 0.1 * sigma);

  // 500 Hz: every other step
  c.profile.rate_gyro.rate_hz = 500.0;
  World half(c);
  half.Reset(s);
  half.Step();
  EXPECT_TRUE(OfType<GyroSample>(half.TakeDelivered()).empty());
  half.Step();
  EXPECT_EQ(OfType<GyroSample>(half.TakeDelivered()).size(), 1u);
}

}  // namespace
}  // namespace hpa::sim
