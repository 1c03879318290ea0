// The fault component: each mode's effect on a delivered stream (synthetic messages, exact
// expectations), its determinism per seed, and its effect on the world's motors and gripper.
#include "hpa/sim/faults.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "hpa/models/camera_model.h"
#include "hpa/sim/world.h"
#include "sim/tests/default_world_config.h"

namespace hpa::sim {
namespace {

// A VIO sample captured at t_s at position (t_s, 0, 1).
SensorMessage Vio(double t_s) {
  VioSample v;
  v.time_s = t_s;
  v.p_WB_W = Eigen::Vector3d(t_s, 0, 1);
  return v;
}

// A fault of `component` in `mode` over [start_s, end_s).
Fault MakeFault(FaultComponent component, FaultMode mode, double start_s, double end_s) {
  Fault f;
  f.component = component;
  f.mode = mode;
  f.start_s = start_s;
  f.end_s = end_s;
  return f;
}

// Delivers VIO samples captured every 10 ms from 0 to 1 s (each at its capture time) through
// `faults`, returning what came out.
std::vector<VioSample> Stream(Faults* faults, double until_s = 1.0) {
  std::vector<VioSample> out;
  for (int k = 0; k * 0.01 <= until_s + 1e-9; ++k) {
    std::vector<SensorMessage> m = {Vio(k * 0.01)};
    faults->FilterDelivered(k * 0.01, &m);
    for (const SensorMessage& s : m) out.push_back(std::get<VioSample>(s));
  }
  std::vector<SensorMessage> rest;
  faults->TakeHeld(&rest);
  for (const SensorMessage& s : rest) out.push_back(std::get<VioSample>(s));
  return out;
}

TEST(FaultsTest, EveryComponentAndModeIsDeclaredOnceWithItsKeys) {
  std::set<std::string> components;
  for (const FaultComponentDecl& c : FaultComponents()) {
    EXPECT_TRUE(components.insert(c.name).second) << c.name;
    std::set<std::string> modes;
    for (const FaultModeDecl& m : c.modes) {
      EXPECT_TRUE(modes.insert(m.name).second) << c.name << " " << m.name;
      EXPECT_FALSE(m.description.empty());
      for (const FaultKeyDecl& k : m.keys) {
        EXPECT_NE(k.number == nullptr, k.vector == nullptr) << k.key;
        EXPECT_LE(k.min, k.max) << k.key;
      }
    }
  }
  EXPECT_EQ(components, (std::set<std::string>{"vio", "imu", "rate_gyro", "motor", "gripper",
                                               "payload_camera"}));
}

TEST(FaultsTest, OffDropsExactlyTheSamplesCapturedInItsWindow) {
  Faults faults(1);
  faults.Inject(MakeFault(FaultComponent::kVio, FaultMode::kOff, 0.2, 0.5));
  const std::vector<VioSample> out = Stream(&faults);
  EXPECT_EQ(out.size(), 101u - 30u);
  for (const VioSample& v : out) EXPECT_TRUE(v.time_s < 0.2 - 1e-9 || v.time_s > 0.5 - 1e-9);
}

TEST(FaultsTest, AFaultOfAnotherComponentLeavesTheStreamAlone) {
  Faults faults(1);
  faults.Inject(MakeFault(FaultComponent::kImu, FaultMode::kStuck, 0.0, 1.0));
  faults.Inject(MakeFault(FaultComponent::kCamera, FaultMode::kOff, 0.0, 1.0));
  EXPECT_EQ(Stream(&faults).size(), 101u);
}

TEST(FaultsTest, DelayedHoldsEachSampleForItsDelayAndNoneOvertakes) {
  Faults faults(1);
  Fault f = MakeFault(FaultComponent::kVio, FaultMode::kDelayed, 0.2, 0.5);
  f.delay_s = 0.1;
  faults.Inject(f);
  std::vector<double> delivered_at;
  std::vector<double> captured;
  for (int k = 0; k <= 100; ++k) {
    std::vector<SensorMessage> m = {Vio(k * 0.01)};
    faults.FilterDelivered(k * 0.01, &m);
    for (const SensorMessage& s : m) {
      delivered_at.push_back(k * 0.01);
      captured.push_back(std::get<VioSample>(s).time_s);
    }
  }
  ASSERT_EQ(captured.size(), 101u);
  for (size_t i = 0; i < captured.size(); ++i) {
    if (i > 0) EXPECT_GT(captured[i], captured[i - 1]);  // in order
    const bool in_window = captured[i] >= 0.2 - 1e-9 && captured[i] < 0.5 - 1e-9;
    if (in_window) EXPECT_NEAR(delivered_at[i] - captured[i], 0.1, 1e-9);
  }
}

TEST(FaultsTest, SlowKeepsSamplesAtItsRate) {
  Faults faults(1);
  Fault f = MakeFault(FaultComponent::kVio, FaultMode::kSlow, 0.0, 1.0);
  f.rate_hz = 20.0;
  faults.Inject(f);
  const std::vector<VioSample> out = Stream(&faults, 0.99);
  ASSERT_EQ(out.size(), 20u);  // 100 Hz in, 20 Hz out
  for (size_t i = 1; i < out.size(); ++i)
    EXPECT_NEAR(out[i].time_s - out[i - 1].time_s, 0.05, 1e-9);
}

TEST(FaultsTest, IntermittentDropsItsShareAndRepeatsPerSeed) {
  const auto kept = [](uint64_t seed) {
    Faults faults(seed);
    Fault f = MakeFault(FaultComponent::kVio, FaultMode::kIntermittent, 0.0, 1e9);
    f.drop_fraction = 0.3;
    faults.Inject(f);
    std::vector<double> times;
    for (int k = 0; k < 10000; ++k) {
      std::vector<SensorMessage> m = {Vio(k * 0.01)};
      faults.FilterDelivered(k * 0.01, &m);
      for (const SensorMessage& s : m) times.push_back(std::get<VioSample>(s).time_s);
    }
    return times;
  };
  const std::vector<double> a = kept(1);
  // binomial: 10000 draws at 0.7 kept have a standard deviation of 46 samples; 300 is 6.5 of them
  EXPECT_NEAR(static_cast<double>(a.size()), 7000.0, 300.0);
  EXPECT_EQ(a, kept(1));  // the same seed, the same drops
  EXPECT_NE(a, kept(2));
}

TEST(FaultsTest, StuckRepeatsTheFirstSampleWithFreshTimeStamps) {
  Faults faults(1);
  faults.Inject(MakeFault(FaultComponent::kVio, FaultMode::kStuck, 0.2, 0.5));
  for (const VioSample& v : Stream(&faults)) {
    const bool in_window = v.time_s >= 0.2 - 1e-9 && v.time_s < 0.5 - 1e-9;
    EXPECT_DOUBLE_EQ(v.p_WB_W.x(), in_window ? 0.2 : v.time_s) << v.time_s;
  }
}

TEST(FaultsTest, WrongVioJumpsByItsOffsetWhileItLasts) {
  Faults faults(1);
  Fault f = MakeFault(FaultComponent::kVio, FaultMode::kWrong, 0.2, 0.5);
  f.offset_W_m = Eigen::Vector3d(0, 2, 0);
  faults.Inject(f);
  for (const VioSample& v : Stream(&faults)) {
    const bool in_window = v.time_s >= 0.2 - 1e-9 && v.time_s < 0.5 - 1e-9;
    EXPECT_DOUBLE_EQ(v.p_WB_W.y(), in_window ? 2.0 : 0.0);
  }
}

TEST(FaultsTest, BiasAndNoiseChangeTheImuAndRateGyroSamples) {
  Faults faults(1);
  Fault bias = MakeFault(FaultComponent::kImu, FaultMode::kBias, 0.0, 1.0);
  bias.gyro_bias_B_radps = Eigen::Vector3d(0.1, 0, 0);
  bias.accel_bias_B_mps2 = Eigen::Vector3d(0, 0, -1);
  faults.Inject(bias);
  Fault noise = MakeFault(FaultComponent::kRateGyro, FaultMode::kNoise, 0.0, 1.0);
  noise.gyro_noise_radps = 0.5;
  faults.Inject(noise);
  std::vector<SensorMessage> m = {ImuSample{0.5, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()},
                                  GyroSample{0.5, Eigen::Vector3d::Zero()}};
  faults.FilterDelivered(0.5, &m);
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(std::get<ImuSample>(m[0]).gyro_B_radps, Eigen::Vector3d(0.1, 0, 0));
  EXPECT_EQ(std::get<ImuSample>(m[0]).accel_B_mps2, Eigen::Vector3d(0, 0, -1));
  EXPECT_GT(std::get<GyroSample>(m[1]).gyro_B_radps.norm(), 0.0);
}

TEST(FaultsTest, MotorFactorsScaleTheFaultyRotorOnlyInItsWindow) {
  Faults faults(1);
  Eigen::Vector4d factor;
  EXPECT_FALSE(faults.MotorThrustFactors(0.0, &factor));
  Fault loss = MakeFault(FaultComponent::kMotor, FaultMode::kLoss, 1.0, 2.0);
  loss.motor = 2;
  loss.loss = 0.4;
  faults.Inject(loss);
  ASSERT_TRUE(faults.MotorThrustFactors(1.5, &factor));
  EXPECT_EQ(factor, Eigen::Vector4d(1, 1, 0.6, 1));
  ASSERT_TRUE(faults.MotorThrustFactors(2.5, &factor));
  EXPECT_EQ(factor, Eigen::Vector4d::Ones());
}

TEST(FaultsTest, ADistractorMovesAtItsVelocityOnlyInItsWindow) {
  Faults faults(1);
  EXPECT_TRUE(faults.DistractorsDrawn(0.0).empty());
  Fault d = MakeFault(FaultComponent::kCamera, FaultMode::kDistractor, 1.0, 3.0);
  d.distractor_W_m = Eigen::Vector3d(0.4, 0, 0.6);
  d.distractor_velocity_W_mps = Eigen::Vector3d(-0.2, 0, 0);
  faults.Inject(d);
  EXPECT_TRUE(faults.DistractorsDrawn(0.5).empty());
  const std::vector<DistractorDraw> at_2 = faults.DistractorsDrawn(2.0);
  ASSERT_EQ(at_2.size(), 1u);
  EXPECT_NEAR(at_2[0].p_W_m[0], 0.2, 1e-12);
  EXPECT_EQ(at_2[0].p_W_m[2], 0.6);
  EXPECT_EQ(at_2[0].sign_size_m, (std::array<double, 3>{0, 0, 0}));  // the payload's sphere
  EXPECT_TRUE(faults.DistractorsDrawn(3.0).empty());
  // a sign: its box size reaches the renderer
  Faults sign_faults(1);
  d.distractor_sign_size_m = Eigen::Vector3d(0.2, 0.1, 0.01);
  sign_faults.Inject(d);
  EXPECT_EQ(sign_faults.DistractorsDrawn(2.0).at(0).sign_size_m,
            (std::array<double, 3>{0.2, 0.1, 0.01}));
}

// The frames of a camera captured at 30 Hz for `seconds` from t = 0 in which `faults` draws a
// distractor.
std::vector<bool> DrawnFrames(const Faults& faults, double seconds) {
  std::vector<bool> drawn;
  for (int k = 0; k < static_cast<int>(seconds * 30.0); ++k) {
    drawn.push_back(!faults.DistractorsDrawn(k / 30.0).empty());
  }
  return drawn;
}

TEST(FaultsTest, AFlickeringDistractorIsDrawnInItsShareOfFramesTheSameForTheSameSeed) {
  Fault d = MakeFault(FaultComponent::kCamera, FaultMode::kDistractor, 0.0, 1e9);
  d.distractor_visible_fraction = 0.3;
  Faults faults(7), same_seed(7), other_seed(8);
  faults.Inject(d);
  same_seed.Inject(d);
  other_seed.Inject(d);
  const std::vector<bool> drawn = DrawnFrames(faults, 100.0);  // 3000 frames
  const double share = std::count(drawn.begin(), drawn.end(), true) / 3000.0;
  // binomial: the standard deviation of the share of 3000 draws at 0.3 is 0.0084; 4 of them
  EXPECT_NEAR(share, 0.3, 0.034);
  EXPECT_EQ(drawn, DrawnFrames(same_seed, 100.0));
  EXPECT_NE(drawn, DrawnFrames(other_seed, 100.0));
  // every render of one instant agrees (a region, the whole frame, the chase camera)
  for (int k = 0; k < 30; ++k) {
    EXPECT_EQ(faults.DistractorsDrawn(k / 30.0).size(), faults.DistractorsDrawn(k / 30.0).size());
  }
  // 1: every frame; 0: none
  for (const double rate : {0.0, 1.0}) {
    Faults f(7);
    d.distractor_visible_fraction = rate;
    f.Inject(d);
    const std::vector<bool> all = DrawnFrames(f, 10.0);
    EXPECT_EQ(std::count(all.begin(), all.end(), true), rate == 1.0 ? 300 : 0);
  }
}

TEST(FaultsTest, ADetectionOnTheDistractorIsCountedAsFalse) {
  const Params params = DefaultConfig().params;
  // hovering: the payload 0.5 m below the vehicle, the distractor 0.15 m beside it
  SystemState truth;
  truth.p_WQ_W = Eigen::Vector3d(0, 0, 1.2);
  truth.p_WL_W = Eigen::Vector3d(0, 0, 1.2 - params.cable_length_m);
  Fault d = MakeFault(FaultComponent::kCamera, FaultMode::kDistractor, 0.0, 1.0);
  d.distractor_W_m = truth.p_WL_W + Eigen::Vector3d(0.15, 0, 0);
  Faults faults(1);
  faults.Inject(MakeFault(FaultComponent::kVio, FaultMode::kOff, 0.0, 1.0));
  faults.Inject(d);
  // a detection at the payload, one at the distractor, none, and one after the window
  SystemState at_distractor = truth;
  at_distractor.p_WL_W = d.distractor_W_m;
  const Eigen::Vector3d on_payload_C = PayloadInCamera_C(params, truth);
  const Eigen::Vector3d on_distractor_C = PayloadInCamera_C(params, at_distractor);
  for (const auto& [t_s, p_C] :
       std::vector<std::pair<double, std::optional<Eigen::Vector3d>>>{{0.0, on_payload_C},
                                                                      {0.1, on_distractor_C},
                                                                      {0.2, std::nullopt},
                                                                      {1.0, on_distractor_C}}) {
    std::optional<PayloadDetection> detection = PayloadDetection{};
    detection->time_s = t_s;
    detection->found = p_C.has_value();
    if (p_C) detection->p_CL_C = *p_C;
    faults.OnCameraReading(t_s, truth, params, true, &detection);
  }
  const std::vector<FaultFrameTally> tallies = faults.FrameTallies();
  ASSERT_EQ(tallies.size(), 2u);
  EXPECT_FALSE(tallies[0].distractor);
  EXPECT_EQ(tallies[0].frames, 0);
  const FaultFrameTally& t = tallies[1];
  EXPECT_TRUE(t.distractor);
  EXPECT_EQ(t.frames, 3);
  EXPECT_EQ(t.drawn_frames, 3);
  EXPECT_EQ(t.in_image_frames, 3);
  EXPECT_EQ(t.detections, 2);
  EXPECT_EQ(t.detections_on_distractor, 1);
}

// The vehicle at hover command for 0.3 s with rotor 0 off from the start: it rolls and falls,
// where the healthy vehicle stays level (the hover command is the world's exact hover speed).
TEST(FaultsTest, AMotorOffTipsTheVehicle) {
  const auto tilt_after = [](bool motor_off) {
    World world(DefaultConfig());
    if (motor_off) {
      Fault off = MakeFault(FaultComponent::kMotor, FaultMode::kOff, 0.0, 1e9);
      off.motor = 0;
      world.faults().Inject(off);
    }
    world.SetMotorSpeedCommand(InputVector::Constant(world.world_params().HoverMotorSpeedRadps()));
    for (int k = 0; k < 300; ++k) world.Step();
    const Truth t = world.GetTruth();
    return std::acos(std::min(1.0, (t.state.q_WB * Eigen::Vector3d::UnitZ()).z()));
  };
  EXPECT_LT(tilt_after(false), 1e-3);
  EXPECT_GT(tilt_after(true), 0.3);  // rad: a quarter of the thrust gone tips it in 0.3 s
}

TEST(FaultsTest, ALateGripperReleasesAtItsEndAndAnEarlyOneAtItsStart) {
  World world(DefaultConfig());
  world.gripper().Grab();
  world.faults().Inject(MakeFault(FaultComponent::kGripper, FaultMode::kLate, 0.0, 0.05));
  world.gripper().Release();
  EXPECT_TRUE(world.gripper().active());
  for (int k = 0; k < 49; ++k) world.Step();
  EXPECT_TRUE(world.gripper().active());
  world.Step();
  world.Step();
  EXPECT_FALSE(world.gripper().active());

  world.gripper().Grab();
  world.faults().Inject(
      MakeFault(FaultComponent::kGripper, FaultMode::kEarly, world.time_s(), world.time_s()));
  world.Step();
  EXPECT_FALSE(world.gripper().active());
}

}  // namespace
}  // namespace hpa::sim
