// The flight profile's latencies in the runner: a command that reaches the rate loop later, or an
// older estimate, makes the same push cost more; zero latency is the ideal world's loop.
#include <gtest/gtest.h>

#include <cstdio>

#include "hpa/models/params.h"
#include "hpa/scenarios/runner.h"
#include "hpa/scenarios/scenario.h"

namespace hpa {
namespace {

// hpa_mpc hovering with ground truth in the ideal world, the quadrotor pushed sideways at 1 s.
Scenario PushedHover() {
  Scenario s;
  s.name = "latency";
  s.duration_s = 3.0;
  s.estimation.ground_truth = true;
  s.estimation.camera = "analytic";
  EventSpec push;
  push.at_s = 1.0;
  push.type = "impulse";
  auto impulse = std::make_shared<ImpulseEvent>();
  impulse->impulse_W_Ns = Eigen::Vector3d(0.3, 0, 0);
  impulse->on_payload = false;
  push.action = impulse;
  s.events.push_back(push);
  return s;
}

double Deviation(const Scenario& s) {
  const RunResult r = RunScenario(s, LoadParams(DefaultParamsPath()), RunOptions{});
  EXPECT_FALSE(r.metrics.crashed);
  EXPECT_FALSE(r.metrics.run_error.has_value());
  return r.metrics.quad_position_deviation_max_m;
}

TEST(LatencyTest, LateCommandsAndOldEstimatesCostTracking) {
  const double none = Deviation(PushedHover());
  Scenario late_command = PushedHover();
  late_command.world.latency.compute_s = 0.05;
  Scenario old_estimate = PushedHover();
  old_estimate.world.latency.estimate_s = 0.05;
  const double with_compute = Deviation(late_command);
  const double with_estimate = Deviation(old_estimate);
  std::printf("[measured] deviation: none %.4f m, 50 ms compute %.4f m, 50 ms estimate %.4f m\n",
              none, with_compute, with_estimate);
  // a 50 ms delay in the loop lets the push carry the vehicle further: measured +16 % (compute)
  // and +15 % (estimate); the bound asks for half of that
  EXPECT_GT(with_compute, 1.08 * none);
  EXPECT_GT(with_estimate, 1.08 * none);
}

TEST(LatencyTest, RunsAreDeterministicWithLatency) {
  Scenario s = PushedHover();
  s.world.latency = {0.00667, 0.002, 0.002};
  EXPECT_EQ(Deviation(s), Deviation(s));
}

}  // namespace
}  // namespace hpa
