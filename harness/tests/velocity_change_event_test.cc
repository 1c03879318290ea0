// The velocity_change event (dv added to one body's velocity at once, the other body untouched
// but through the cable) and the impulse event's warning about an implausible push.

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>

#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/scenarios/events.h"
#include "hpa/scenarios/runner.h"
#include "hpa/scenarios/scenario.h"
#include "hpa/sim/world.h"
#include "models/tests/temp_dir.h"
#include "sim/tests/default_world_config.h"

namespace hpa {
namespace {

// A short scenario flying `events` (YAML list items, each line indented by two spaces).
Scenario Load(const std::string& events) {
  const std::string path = TestTempDir() + "velocity_change.yaml";
  std::ofstream(path) << "name: vc\nduration: 0.3\ncontroller: {type: geometric}\n"
                         "estimation: {ground_truth: true, camera: analytic}\nevents:\n"
                      << events;
  return LoadScenario(path);
}

// A hovering quadrotor 2 m up with the payload 0.3 m below it: the cable (0.5 m) is slack, so
// only gravity acts on the payload and the two bodies do not pull on each other.
void HoverWithSlackPayload(sim::World* world) {
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0, 0, 2);
  s.p_WL_W = Eigen::Vector3d(0, 0, 1.7);
  world->SetState(s.ToVector(),
                  InputVector::Constant(world->world_params().HoverMotorSpeedRadps()));
}

// Applies a velocity change of dv_W_mps to one body and checks both bodies at once and a step
// later.
void CheckVelocityChange(bool on_payload, const Eigen::Vector3d& dv_W_mps) {
  sim::World world(sim::DefaultConfig());
  HoverWithSlackPayload(&world);
  const SystemState before = world.GetTruth().state;
  VelocityChangeEvent event;
  event.on_payload = on_payload;
  event.dv_W_mps = dv_W_mps;
  event.Apply(&world);
  const SystemState now = world.GetTruth().state;
  const Eigen::Vector3d& pushed_before_W = on_payload ? before.v_WL_W : before.v_WQ_W;
  const Eigen::Vector3d& pushed_now_W = on_payload ? now.v_WL_W : now.v_WQ_W;
  const Eigen::Vector3d& other_before_W = on_payload ? before.v_WQ_W : before.v_WL_W;
  const Eigen::Vector3d& other_now_W = on_payload ? now.v_WQ_W : now.v_WL_W;
  // at once: exactly dv on the pushed body, nothing on the other
  EXPECT_LT((pushed_now_W - pushed_before_W - dv_W_mps).norm(), 1e-12);
  EXPECT_EQ(other_now_W, other_before_W);

  // a step later the change is still dv, up to the step's gravity and thrust (g dt = 0.01 m/s at
  // 1 kHz); the slack cable passes nothing to the other body
  world.Step();
  const SystemState after = world.GetTruth().state;
  const double dt_s = sim::World::kPhysicsDt_s;
  const double g_dt_mps = world.world_params().gravity_mps2 * dt_s;
  const Eigen::Vector3d& pushed_after_W = on_payload ? after.v_WL_W : after.v_WQ_W;
  const Eigen::Vector3d& other_after_W = on_payload ? after.v_WQ_W : after.v_WL_W;
  EXPECT_LT((pushed_after_W - pushed_before_W - dv_W_mps).norm(), 2 * g_dt_mps);
  EXPECT_LT((other_after_W - other_before_W).norm(), 2 * g_dt_mps);
}

TEST(VelocityChangeEventTest, ChangesThePayloadsVelocityByDv) {
  CheckVelocityChange(true, Eigen::Vector3d(0.5, -0.2, 0.3));
}

TEST(VelocityChangeEventTest, ChangesTheQuadrotorsVelocityByDv) {
  CheckVelocityChange(false, Eigen::Vector3d(-0.4, 0.1, 0.2));
}

TEST(VelocityChangeEventTest, ParsesAndRejectsAnImplausibleDv) {
  const Scenario s = Load("  - {at: 0.1, type: velocity_change, body: quadrotor, dv: [1, 0, 0]}\n");
  ASSERT_EQ(s.events.size(), 1u);
  const auto* event = dynamic_cast<const VelocityChangeEvent*>(s.events[0].action.get());
  ASSERT_NE(event, nullptr);
  EXPECT_FALSE(event->on_payload);
  EXPECT_EQ(event->dv_W_mps, Eigen::Vector3d(1, 0, 0));
  try {
    Load("  - {at: 0.1, type: velocity_change, dv: [25, 0, 0]}\n");
    FAIL() << "accepted a 25 m/s velocity change";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("events.0.dv"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Load("  - {at: 0.1, type: velocity_change, dv: [.nan, 0, 0]}\n"), InputError);
  EXPECT_THROW(Load("  - {at: 0.1, type: velocity_change, dv: [1, 0]}\n"), InputError);
}

// The run's stderr while it flies `events`.
std::string RunStderr(const std::string& events) {
  const Params params = LoadParams(DefaultParamsPath());
  const Scenario scenario = Load(events);
  testing::internal::CaptureStderr();
  RunScenario(scenario, params, RunOptions{});
  return testing::internal::GetCapturedStderr();
}

TEST(VelocityChangeEventTest, AnImplausibleImpulseWarnsOnceAtRunStart) {
  // 2 N s on the (about) 0.1 kg payload is about 20 m/s, beyond the plausible 10 m/s
  const std::string warned =
      RunStderr("  - {at: 0.25, type: impulse, body: payload, impulse: [0, 0, 2]}\n");
  const std::string line = "events.0 (impulse at 0.25 s): 2 N s on the payload";
  ASSERT_NE(warned.find(line), std::string::npos) << warned;
  EXPECT_EQ(warned.find(line, warned.find(line) + 1), std::string::npos) << "warned twice";
  // the world's payload mass is the flight profile's draw around 0.1 kg: about 20 m/s
  EXPECT_NE(warned.find("beyond a plausible 10 m/s"), std::string::npos) << warned;
  // 0.5 N s on it is 5 m/s, and 2 N s on the 0.72 kg quadrotor 2.8 m/s: no warning
  const std::string quiet = RunStderr(
      "  - {at: 0.25, type: impulse, body: payload, impulse: [0, 0, 0.5]}\n"
      "  - {at: 0.25, type: impulse, body: quadrotor, impulse: [0, 0, 2]}\n");
  EXPECT_EQ(quiet.find("warning"), std::string::npos) << quiet;
}

}  // namespace
}  // namespace hpa
