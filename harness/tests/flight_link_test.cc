// The in-process flight link states the control rate its controller runs at (the runner sizes
// the run's log with it).
#include "harness/runner/src/flight_link.h"

#include <gtest/gtest.h>

#include "hpa/models/params.h"
#include "hpa/scenarios/scenario.h"
#include "harness/runner/src/run_loop.h"

namespace hpa {
namespace {

TEST(FlightLinkTest, InProcessStackStatesItsControllersRate) {
  const Params params = LoadParams(DefaultParamsPath());
  Scenario scenario;
  scenario.estimation.ground_truth = true;
  const SystemState initial;
  // the rates the controllers declare (MpcSettings::rate_hz, GeometricController::RateHz)
  for (const std::string type : {"hpa_mpc", "geometric"}) {
    scenario.controller.type = type;
    const std::unique_ptr<runner::FlightLink> link =
        runner::MakeInProcessFlight(runner::FlightConfigOf(scenario, params, initial));
    EXPECT_EQ(link->control_rate_hz(), 150.0) << type;
  }
}

}  // namespace
}  // namespace hpa
