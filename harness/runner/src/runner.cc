#include "hpa/scenarios/runner.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <deque>
#include <random>
#include <sstream>
#include <thread>

#include "hpa/controller/team_controller.h"
#include "hpa/sim/team_world.h"
#include "hpa/sim/world.h"
#include "harness/runner/src/run_loop.h"

namespace hpa {
namespace {
volatile std::sig_atomic_t g_stop_signal = 0;  // set from a signal handler
}  // namespace

int runner::StopSignal() { return g_stop_signal; }

void RequestStop(int signal_number) { g_stop_signal = signal_number; }

bool ControlThreadPays() { return std::thread::hardware_concurrency() >= 2; }

int StopRequested() { return g_stop_signal; }

RateTable ScenarioRates(const Scenario& scenario) {
  RateTable rates;
  rates.camera.latency_s = scenario.estimation.camera_latency_s;
  return rates;
}

namespace {

// A team's own streams (RunTeamScenario): the motion-capture system (or the truth) that sees
// the payload and, unless its vehicles estimate on board, each vehicle's own state and gyro.
void AddTeamStreams(const Scenario& scenario, bool onboard, std::vector<RateRow>* rows) {
  const sim::MocapConfig mocap;
  const auto number = [](double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", value);
    return std::string(text);
  };
  if (scenario.estimation.ground_truth) {
    rows->push_back({"ground truth (every body)", 1.0 / sim::World::kPhysicsDt_s, 0.0,
                     "estimation.ground_truth", ""});
    return;
  }
  rows->push_back({onboard ? "motion capture (the payload)" : "motion capture (every body)",
                   mocap.rate_hz, mocap.latency_s, "sim::MocapConfig",
                   "position " + number(mocap.position_noise_m) + " m, velocity " +
                       number(mocap.velocity_noise_mps) + " m/s, attitude " +
                       number(mocap.attitude_noise_rad) + " rad"});
  if (!onboard) {
    rows->push_back({"rate gyro (each vehicle)", 1.0 / sim::World::kPhysicsDt_s, 0.0,
                     "sim::MocapConfig", number(mocap.rate_gyro_noise_radps) + " rad/s"});
  }
}

}  // namespace

std::vector<RateRow> ScenarioRateTable(const Scenario& scenario, const Params& params) {
  const bool team = scenario.team.IsTeam();
  const bool onboard = !team || (!scenario.estimation.ground_truth &&
                                 scenario.estimation.vehicle_state == "onboard");
  const bool cameras = team ? scenario.team.payload_cameras : !scenario.estimation.ground_truth;
  const std::string each = team ? ", each vehicle" : "";
  const sim::LatencyProfile& latency = scenario.world.latency;
  double control_hz = 0.0;
  if (team) {
    CooperativeTeam cooperative;
    for (const VehicleSpec& v : scenario.team.vehicles) {
      cooperative.vehicles.push_back({params, v.cable_length_m, v.p_PA_P_m});
    }
    control_hz = MakeTeamController(scenario.controller.type, cooperative, 0,
                                    MakeReference(scenario, params))
                     ->RateHz();
  } else {
    control_hz =
        MakeController(scenario.controller, params, MakeReference(scenario, params))->RateHz();
  }
  // the sensors as the world declares them, for this scenario's world (a team vehicle's
  // onboard ones with its vehicle_state: onboard)
  sim::WorldConfig world;
  world.rates = ScenarioRates(scenario);
  world.profile = scenario.world;
  std::vector<RateRow> rows = {{"physics", 1.0 / sim::World::kPhysicsDt_s, 0.0,
                                "MuJoCo timestep (sim::World::kPhysicsDt_s)", ""}};
  if (team) AddTeamStreams(scenario, onboard, &rows);
  for (const sim::SensorDeclaration& s : sim::SensorDeclarations(world)) {
    if (s.name == "payload camera") {
      if (!cameras) continue;  // the flight code reads the truth, or a team flies none
      rows.push_back({s.name + " (" + scenario.estimation.camera + each + ")", s.rate_hz,
                      s.latency_s, s.from, s.noise});
    } else if (s.name == "wind") {
      rows.push_back({s.name, s.rate_hz, s.latency_s, s.from, s.noise});  // on every body
    } else if (!team || (onboard && s.name.rfind("gripper", 0) != 0)) {
      rows.push_back(
          {team ? s.name + " (each vehicle)" : s.name, s.rate_hz, s.latency_s, s.from, s.noise});
    }
  }
  if (scenario.rate_loop.px4 && onboard) {
    rows.push_back({"rate loop (PX4's, on the rate gyro" + each + ")",
                    scenario.rate_loop.params.rate_hz, 0.0,
                    "rate_loop.rate_hz (PX4's parameters, flight code)", ""});
  } else {
    const std::string kind = scenario.rate_loop.px4 ? "PX4's" : "body-rate P";
    const std::string on = onboard ? "on the IMU" : "on its gyro";
    rows.push_back({"rate loop (" + kind + ", " + on + each + ")", world.rates.imu.rate_hz, 0.0,
                    "RateTable::imu", ""});
  }
  rows.push_back({"control (" + scenario.controller.type + each + ")", control_hz,
                  latency.compute_s + latency.transport_s,
                  "the controller's RateHz(); world profile latency.compute_s + transport_s", ""});
  rows.push_back(
      {"estimate to controller", 0.0, latency.estimate_s, "world profile latency.estimate_s", ""});
  rows.push_back({"video (--video)", world.rates.video.rate_hz, 0.0, "RateTable::video", ""});
  return rows;
}

void WriteRunLogCsv(const std::string& path, const RunResult& result) {
  if (result.metrics.team) {
    WriteTeamLogCsv(path, result.team_rows, static_cast<int>(result.metrics.vehicles.size()));
  } else {
    WriteLogCsv(path, result.rows);
  }
}

Params WorldParams(const Scenario& scenario, const Params& params) {
  Params p = params;
  if (scenario.world_payload_mass_kg) p.payload_mass_kg = *scenario.world_payload_mass_kg;
  if (scenario.world_cable_length_m) p.cable_length_m = *scenario.world_cable_length_m;
  return p;
}

namespace {

// Flies one vehicle's scenario (RunLoop) and checks its expect bounds.
RunResult RunSingleScenario(const Scenario& scenario, const Params& base_params,
                            const RunOptions& options) {
  // the scenario's params: block changes the flight code's model and the world alike
  const Params params = ScenarioParams(scenario, base_params);
  RunResult result;
  Metrics& metrics = result.metrics;
  metrics.scenario = scenario.name;
  // what flies: a separate stack names itself in its hello (RunLoop); one that never does is
  // "external", never the scenario's controller it did not fly
  const bool external = !options.flight_stack.empty();
  metrics.controller = external ? "external" : scenario.controller.type;
  if (external) metrics.flight_stack = "external";
  metrics.camera = scenario.estimation.ground_truth ? "ground_truth" : scenario.estimation.camera;
  metrics.seed = scenario.seed;
  metrics.world_profile = scenario.world.name;
  metrics.payload_rmse_from_s = RmseFromS(scenario.reference);
  // the camera faults' frame tallies, read from the world when the run stops (the metrics of
  // their fault events)
  std::vector<sim::FaultFrameTally> tallies;
  RunOptions run_options = options;
  run_options.at_stop = [&](sim::World& world) {
    tallies = world.faults().FrameTallies();
    if (options.at_stop) options.at_stop(world);
  };
  std::unique_ptr<runner::RunLoop> loop;
  try {
    loop = std::make_unique<runner::RunLoop>(scenario, params, run_options, &metrics);
  } catch (const flight::ProtocolError& e) {
    // a separate flight stack that did not start: a run error, nothing flown
    metrics.run_error = e.what();
    return result;
  }
  try {
    loop->Run();
  } catch (const std::exception& e) {
    // keep what was computed: the metrics of the run so far, with the error named
    metrics.run_error =
        std::string(e.what()) + " (at t = " + std::to_string(loop->time_s()) + " s)";
  }
  loop->Finish(&result);
  if (AddFaultFrameTallies(tallies, &metrics)) CheckExpectations(scenario.expect, &metrics);
  return result;
}

// The verdict's last word, for every kind of run: a run with a run error never passes, and one
// that stopped before its first control step (a flight stack that did not start, say hello or
// answer its first tick) fails first of all as never flown, whatever its bounds read.
void FailRunsThatDidNotFly(Metrics* m) {
  if (!m->run_error) return;
  if (m->control_steps == 0) {
    const std::string aborted = "run aborted: " + *m->run_error;
    std::vector<std::string>& failed = m->expect_failed;
    failed.erase(std::remove(failed.begin(), failed.end(), aborted), failed.end());
    failed.insert(failed.begin(), "never flew: " + *m->run_error);
  } else if (m->expect_failed.empty()) {
    m->expect_failed.push_back("run aborted: " + *m->run_error);
  }
  m->expect_passed = false;
}

}  // namespace

RunResult RunScenario(const Scenario& scenario, const Params& base_params,
                      const RunOptions& options) {
  RunResult result = scenario.team.IsTeam() ? RunTeamScenario(scenario, base_params, options)
                                            : RunSingleScenario(scenario, base_params, options);
  FailRunsThatDidNotFly(&result.metrics);
  return result;
}

}  // namespace hpa
