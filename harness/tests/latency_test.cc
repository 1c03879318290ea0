// The flight profile's latencies in the runner: a command that reaches the rate loop later, or an
// older estimate, makes the same push cost more; zero latency is the ideal world's loop.
#include <gtest/gtest.h>

#include <cstdio>
#include <nlohmann/json.hpp>

#include "hpa/models/params.h"
#include "hpa/scenarios/metrics.h"
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

// The metrics of a run without its wall-clock timings.
nlohmann::json MetricsWithoutTimings(const Metrics& metrics) {
  nlohmann::json j = nlohmann::json::parse(MetricsToJson(metrics));
  for (const char* key : {"wall_time_s", "mpc_solve_ms", "render_ms", "detector_ms",
                          "image_model_ms"}) {
    j.erase(key);
  }
  return j;
}

TEST(LatencyTest, ControlThreadFliesTheSameRunAndLogsItInOrder) {
  // the onboard estimator on the analytic camera; no command delay (each command taken at its
  // own tick), the flight profile's, and one that keeps about eight commands on the thread
  const Params params = LoadParams(DefaultParamsPath());
  for (const double compute_s : {0.0, 0.00667, 0.05}) {
    Scenario s = PushedHover();
    s.estimation.ground_truth = false;
    s.world.latency = {compute_s, 0.002, 0.0};
    RunOptions inline_options, threaded_options;
    threaded_options.control_thread = true;
    const RunResult a = RunScenario(s, params, inline_options);
    const RunResult b = RunScenario(s, params, threaded_options);
    EXPECT_FALSE(a.metrics.run_error.has_value()) << compute_s;
    EXPECT_EQ(MetricsWithoutTimings(a.metrics), MetricsWithoutTimings(b.metrics)) << compute_s;
    ASSERT_EQ(a.rows.size(), b.rows.size()) << compute_s;
    ASSERT_GT(a.rows.size(), 400u);  // 150 Hz for 3 s
    for (size_t i = 0; i < a.rows.size(); ++i) {
      const LogRow &x = a.rows[i], &y = b.rows[i];
      ASSERT_EQ(x.time_s, y.time_s) << compute_s << " row " << i;
      EXPECT_EQ(x.command.w_B_radps, y.command.w_B_radps) << compute_s << " row " << i;
      EXPECT_EQ(x.command.thrust_N, y.command.thrust_N) << compute_s << " row " << i;
      EXPECT_EQ(x.status, y.status) << compute_s << " row " << i;
      EXPECT_EQ(x.cost, y.cost) << compute_s << " row " << i;
      EXPECT_EQ(x.estimate.p_WL_W, y.estimate.p_WL_W) << compute_s << " row " << i;
      EXPECT_EQ(x.truth.p_WQ_W, y.truth.p_WQ_W) << compute_s << " row " << i;
      EXPECT_EQ(x.mixer_saturated, y.mixer_saturated) << compute_s << " row " << i;
    }
  }
}

}  // namespace
}  // namespace hpa
