// The closed loop in steady state allocates no heap memory: a whole in-process run (the flight
// profile's world with its sensors and their latencies, PX4's rate loop, the onboard estimator,
// the analytic camera, hpa_mpc, the log) counted between two control steps a simulated second
// and a half apart. Its own binary: global operator new is replaced by a counting one
// (models/tests/support/counting_allocator.h).

#include <gtest/gtest.h>

#include <string>

#include "hpa/models/params.h"
#include "hpa/scenarios/runner.h"
#include "hpa/scenarios/scenario.h"
#include "models/tests/support/counting_allocator.h"

namespace hpa {
namespace {

using test_support::StartCountingAllocations;
using test_support::StopCountingAllocations;

// Counts the allocations made between the first control step at or after from_s and the first at
// or after to_s.
class AllocationWindow final : public RunRecorder {
 public:
  AllocationWindow(double from_s, double to_s) : from_s_(from_s), to_s_(to_s) {}
  void OnControlStep(const LogRow& row) override {
    if (!started_ && row.time_s >= from_s_) {
      started_ = true;
      StartCountingAllocations();
    } else if (started_ && !stopped_ && row.time_s >= to_s_) {
      stopped_ = true;
      allocations_ = StopCountingAllocations();
    }
  }
  bool measured() const { return stopped_; }
  long allocations() const { return allocations_; }

 private:
  double from_s_, to_s_;
  bool started_ = false, stopped_ = false;
  long allocations_ = 0;
};

// A hover on the flight profile with the onboard estimator and the analytic camera.
Scenario Hover(const std::string& controller) {
  return LoadScenarioText(R"(name: hover_allocations
duration: 4.0
seed: 3
controller: {type: )" + controller +
                              R"(}
estimation: {camera: analytic, ground_truth: false}
reference: {type: hover, payload_position: [0, 0, 0.7]}
)",
                          "hover_allocations");
}

TEST(RunLoopAllocationTest, SteadyHoverAllocatesNothing) {
  const Params params = LoadParams(DefaultParamsPath());
  for (const std::string controller : {"hpa_mpc", "nonhybrid_mpc"}) {
    for (const bool control_thread : {false, true}) {
      AllocationWindow window(2.0, 3.5);
      RunOptions options;
      options.recorders.push_back(&window);
      options.control_thread = control_thread;
      const RunResult result = RunScenario(Hover(controller), params, options);
      ASSERT_FALSE(result.metrics.crashed) << controller;
      ASSERT_TRUE(window.measured()) << controller;
      EXPECT_EQ(window.allocations(), 0)
          << controller << (control_thread ? ", control thread" : ", inline");
    }
  }
}

}  // namespace
}  // namespace hpa
