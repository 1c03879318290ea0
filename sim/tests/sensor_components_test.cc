// The world's sensors as components: a sensor added the way MakeSensors adds one is delivered
// after its declared latency; the payload camera fires on its own clock and delivers through the
// same delay lines; the gripper's switch is read at the start of a tick; the wind declares its
// gust and replays it after Reset; the rate table lists them all.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "hpa/models/params.h"
#include "hpa/sim/payload_camera.h"
#include "hpa/sim/sensors.h"
#include "hpa/sim/wind.h"
#include "hpa/sim/world.h"
#include "sim/tests/default_world_config.h"

namespace hpa::sim {
namespace {

// A toy altimeter: the true height as a VIO-shaped sample at 50 Hz, 40 ms late.
class ToyAltimeter final : public Sensor {
 public:
  ToyAltimeter() : declaration_{"toy altimeter", 50.0, 0.04, "none", "the test"} {}
  const SensorDeclaration& declaration() const override { return declaration_; }
  void Reset() override { steps_ = 0; }
  std::optional<SensorMessage> Sample(const SensorInput& in) override {
    if (steps_++ % 20 != 0) return std::nullopt;  // 50 Hz on the 1 kHz physics clock
    VioSample s;
    s.time_s = in.t_k_s;
    s.p_WB_W = Eigen::Vector3d(0, 0, in.state->p_WQ_W.z());
    return s;
  }

 private:
  SensorDeclaration declaration_;
  int steps_ = 0;
};

// The VIO-shaped messages with a zero x and y (the altimeter's) among `messages`.
std::vector<VioSample> AltimeterSamples(const std::vector<SensorMessage>& messages) {
  std::vector<VioSample> out;
  for (const SensorMessage& m : messages) {
    const auto* v = std::get_if<VioSample>(&m);
    if (v != nullptr && v->p_WB_W.x() == 0.0 && v->p_WB_W.y() == 0.0) out.push_back(*v);
  }
  return out;
}

TEST(SensorComponentsTest, AnAddedSensorIsDeliveredAfterItsDeclaredLatency) {
  World world(DefaultConfig());
  world.AddSensor(std::make_unique<ToyAltimeter>());
  EXPECT_EQ(world.sensors().back()->declaration().name, "toy altimeter");
  world.SetMotorSpeedCommand(InputVector::Constant(world.world_params().HoverMotorSpeedRadps()));
  int delivered = 0;
  for (int k = 0; k < 200; ++k) {
    world.Step();
    for (const VioSample& s : AltimeterSamples(world.TakeDelivered())) {
      // captured at a multiple of 20 ms, delivered exactly 40 ms later (to the step)
      EXPECT_NEAR(std::fmod(s.time_s + 1e-9, 0.02), 0.0, 1e-6);
      EXPECT_NEAR(world.time_s() - s.time_s, 0.04, 1e-9);
      EXPECT_NEAR(s.p_WB_W.z(), 1.0, 0.01);  // hovering 1 m up
      ++delivered;
    }
  }
  // captures at 0, 20, ..., 160 ms are due by 200 ms
  EXPECT_EQ(delivered, 9);
}

TEST(SensorComponentsTest, TheAnalyticCameraFiresOnItsClockAndDeliversThroughTheDelayLine) {
  WorldConfig c = DefaultConfig();
  c.camera.kind = CameraKind::kAnalytic;
  World world(c);
  world.SetMotorSpeedCommand(InputVector::Constant(world.world_params().HoverMotorSpeedRadps()));
  std::vector<double> captured_s, delivered_s;
  for (int k = 0; k <= 200; ++k) {
    const bool due = world.CameraFrameDue();
    const std::optional<CameraCapture> capture = world.CaptureTickStart();
    EXPECT_EQ(due, capture.has_value()) << "at step " << k;
    if (capture) {
      EXPECT_FALSE(capture->exposure.has_value());  // no pixels for the flight stack to read
      captured_s.push_back(capture->time_s);
      EXPECT_TRUE(capture->payload_in_image);  // hanging below the camera at hover
      EXPECT_TRUE(capture->detected);
    }
    for (const SensorMessage& m : world.TakeDelivered()) {
      if (const auto* d = std::get_if<PayloadDetection>(&m)) {
        EXPECT_NEAR(world.time_s() - d->time_s, c.rates.camera.latency_s, 1e-9);
        delivered_s.push_back(d->time_s);
      }
    }
    world.Step();
  }
  // 30 Hz at the nearest step: 0, 33, 67, 100, 133, 167, 200 ms
  const std::vector<double> expected = {0.0, 0.033, 0.067, 0.1, 0.133, 0.167, 0.2};
  ASSERT_EQ(captured_s.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) EXPECT_NEAR(captured_s[i], expected[i], 1e-9);
  // delivered 30 ms later: all but the one captured at 200 ms (due at 230 ms)
  EXPECT_EQ(delivered_s.size(), expected.size() - 1);
  EXPECT_EQ(world.payload_camera().declaration().rate_hz, c.rates.camera.rate_hz);
}

TEST(SensorComponentsTest, ACameraWithoutImagesRecordsTheCaptureAndDeliversNothing) {
  World world(DefaultConfig());  // CameraKind::kNone: the ground-truth switch
  const std::optional<CameraCapture> capture = world.CaptureTickStart();
  ASSERT_TRUE(capture.has_value());
  EXPECT_TRUE(capture->payload_in_image);
  EXPECT_FALSE(capture->detected);
  for (int k = 0; k < 100; ++k) world.Step();
  for (const SensorMessage& m : world.TakeInFlight()) {
    EXPECT_FALSE(std::holds_alternative<PayloadDetection>(m));
    EXPECT_FALSE(std::holds_alternative<CameraFrame>(m));
  }
}

TEST(SensorComponentsTest, TheGripperSwitchIsReadAtTheStartOfTheTickThatGrabs) {
  World world(DefaultConfig());
  // the switch of the tick: false, then true from the tick whose event grabbed
  const auto switch_now = [&] {
    world.CaptureTickStart();
    std::optional<bool> active;
    for (const SensorMessage& m : world.TakeDelivered()) {
      if (const auto* g = std::get_if<GripperSample>(&m)) active = g->active;
    }
    return active;
  };
  EXPECT_EQ(switch_now(), std::optional<bool>(false));
  world.Step();
  world.gripper().Grab();
  EXPECT_EQ(switch_now(), std::optional<bool>(true));
  world.Step();
  world.gripper().Release();
  EXPECT_EQ(switch_now(), std::optional<bool>(false));
}

TEST(SensorComponentsTest, TheWindDeclaresItsGustAndReplaysItAfterReset) {
  WindProfile gusty;
  gusty.gust_sigma_mps = 1.5;
  WindModel wind(gusty, 1000.0, 42);
  EXPECT_NE(wind.declaration().noise.find("gust sigma 1.5 m/s"), std::string::npos)
      << wind.declaration().noise;
  const auto run = [&] {
    wind.Reset();
    std::vector<double> x;
    for (int k = 0; k < 100; ++k) {
      wind.StepGust(Eigen::Vector3d(1.0, 0.0, 0.0));
      x.push_back(wind.Wind_W_mps(k).x());
    }
    return x;
  };
  const std::vector<double> first = run();
  EXPECT_EQ(run(), first);
  EXPECT_GT(
      *std::max_element(first.begin(), first.end()) - *std::min_element(first.begin(), first.end()),
      0.0);
  // a wind event adds its velocity for its steps only
  wind.SetEvent(Eigen::Vector3d(2.0, 0.0, 0.0), 100, 10);
  EXPECT_NEAR(wind.Wind_W_mps(105).x() - wind.Wind_W_mps(110).x(), 2.0, 1e-12);
}

TEST(SensorComponentsTest, TheRateTableListsEveryComponent) {
  std::vector<std::string> names;
  for (const SensorDeclaration& d : SensorDeclarations(DefaultConfig())) names.push_back(d.name);
  for (const char* name : {"imu", "vio", "gripper", "payload camera", "wind"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), name), names.end()) << name;
  }
}

}  // namespace
}  // namespace hpa::sim
