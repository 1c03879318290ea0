// The team runner (RunTeamScenario, docs/cooperative.md): N vehicles on their own cables carrying
// one payload. It sets up the team, its start and its flight code, flies the run loop
// (team_run_loop.h) and computes the team's metrics from its log.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <stdexcept>

#include "hpa/controller/team_controller.h"
#include "hpa/models/cooperative_model.h"
#include "hpa/models/input_error.h"
#include "hpa/models/rotor_model.h"
#include "hpa/scenarios/runner.h"
#include "hpa/sim/team_world.h"
#include "harness/runner/src/events/fault_event.h"
#include "harness/runner/src/team_flight_link.h"
#include "harness/runner/src/team_run_loop.h"

namespace hpa {
namespace {

using Index = CooperativeStateIndex;
using Clock = std::chrono::steady_clock;

// The team of a scenario: its payload, and each vehicle the scenario's params on its own cable.
CooperativeTeam TeamOf(const Scenario& scenario, const Params& params) {
  CooperativeTeam team;
  team.payload_mass_kg = scenario.team.payload_mass_kg;
  team.payload_inertia_P_kgm2 = scenario.team.payload_inertia_P_kgm2;
  team.gravity_mps2 = params.gravity_mps2;
  for (const VehicleSpec& spec : scenario.team.vehicles) {
    CooperativeVehicle vehicle;
    vehicle.params = params;
    vehicle.cable_length_m = spec.cable_length_m;
    vehicle.p_PA_P_m = spec.p_PA_P_m;
    team.vehicles.push_back(vehicle);
  }
  return team;
}

// Where a team run starts, at rest: the payload level at the reference's start (resting on the
// ground below it for a lift), each vehicle straight above its attachment point at its cable's
// length less its start slack.
Eigen::VectorXd StartState(const Scenario& scenario, const CooperativeModel& model,
                           const Eigen::Vector3d& p_start_W_m, double payload_radius_m) {
  Eigen::Vector3d p_WL_W = p_start_W_m;
  if (scenario.team.payload_on_ground) p_WL_W.z() = payload_radius_m;
  Eigen::VectorXd x = model.HangingState(p_WL_W);
  for (size_t i = 0; i < scenario.team.vehicles.size(); ++i) {
    x(Index::Vehicle(static_cast<int>(i)) + Index::kVehiclePos + 2) -=
        scenario.team.vehicles[i].start_slack_m;
  }
  return x;
}

// Refuses a start no team can fly from (two vehicles' boxes overlapping: MuJoCo would push them
// apart at once, a crash at t = 0 that says nothing about the controller), and warns when the
// team's full thrust cannot lift the team.
void CheckStart(const Scenario& scenario, const CooperativeTeam& team, const Eigen::VectorXd& x0) {
  const int n = static_cast<int>(team.vehicles.size());
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      const Eigen::Vector3d d_m =
          x0.segment<3>(Index::Vehicle(i)) - x0.segment<3>(Index::Vehicle(j));
      const Eigen::Vector3d reach_m =
          team.vehicles[i].params.body_half_size_m + team.vehicles[j].params.body_half_size_m;
      if ((d_m.cwiseAbs().array() < reach_m.array()).all()) {
        char text[256];
        std::snprintf(text, sizeof text,
                      "vehicles %d and %d start %.3g m apart, their bodies overlapping: place "
                      "their attachment points (attach_m) or start slack farther apart",
                      i, j, d_m.norm());
        throw InputError(scenario.file, "vehicles", text);
      }
    }
  }
  double lift_N = 0.0, weight_N = team.payload_mass_kg * team.gravity_mps2;
  for (const CooperativeVehicle& v : team.vehicles) {
    const Params& p = v.params;
    lift_N += 4.0 * p.RotorThrustMaxN();
    weight_N += p.quad_mass_kg * p.gravity_mps2;
  }
  if (lift_N <= weight_N) {
    std::fprintf(stderr,
                 "warning: %s: the team's full thrust, %.3g N, cannot lift its weight, %.3g N "
                 "(the vehicles and a %.3g kg payload)\n",
                 scenario.name.c_str(), lift_N, weight_N, team.payload_mass_kg);
  }
}

// Whether a status is a failed update (as the single vehicle's mpc_failures counts them).
bool IsFailure(ControlStatus status) {
  return status == ControlStatus::kQpFailure || status == ControlStatus::kNonFinite ||
         status == ControlStatus::kFallback;
}

// The payload's tracking and the team's metrics from the log (crash, timing, separation and the
// physics-rate extremes are the runner's). The payload RMSE follows the single vehicle's rule
// (InPayloadRmse): over the time every cable was taut when one went slack.
void ComputeTeamMetrics(const std::vector<TeamLogRow>& rows, int vehicles,
                        const std::vector<int>& rate_steps, const std::vector<int>& saturated,
                        Metrics* m) {
  m->control_steps = static_cast<int>(rows.size());
  // the single vehicle's quadrotor, estimator, camera and contact metrics: not measured
  MarkUnmeasured(TeamUnmeasuredMetrics(), m);
  if (rows.empty()) return;
  std::vector<double> times_s, all_solve_ms;
  std::vector<CableMode> any_slack;
  std::vector<std::vector<CableMode>> modes(static_cast<size_t>(vehicles));
  std::vector<std::vector<double>> solve_ms(static_cast<size_t>(vehicles));
  for (const TeamLogRow& r : rows) {
    m->payload_max_speed_mps =
        std::max(m->payload_max_speed_mps, r.x_true.segment<3>(Index::kPayloadVel).norm());
    times_s.push_back(r.time_s);
    bool slack = false;
    for (int i = 0; i < vehicles; ++i) {
      const TeamLogRow::Vehicle& v = r.vehicles[static_cast<size_t>(i)];
      VehicleMetrics& vm = m->vehicles[static_cast<size_t>(i)];
      vm.control_failures += IsFailure(v.status) ? 1 : 0;
      modes[static_cast<size_t>(i)].push_back(v.mode);
      solve_ms[static_cast<size_t>(i)].push_back(v.solve_time_ms);
      all_solve_ms.push_back(v.solve_time_ms);
      slack = slack || v.mode == CableMode::kSlack;
    }
    any_slack.push_back(slack ? CableMode::kSlack : CableMode::kTaut);
  }
  // the team's slack: time with at least one cable slack
  const std::vector<std::pair<double, double>> team_slack = SlackIntervals(times_s, any_slack);
  m->slack_time_s = 0.0;
  m->slack_events = 0;
  for (const auto& [start, end] : team_slack) {
    m->slack_time_s += end - start;
    ++m->slack_events;
  }
  // payload RMSE as the single vehicle's
  m->payload_rmse_over = PayloadRmseOver(team_slack);
  Eigen::Vector3d sum_sq = Eigen::Vector3d::Zero();
  int samples = 0;
  for (const TeamLogRow& r : rows) {
    if (!InPayloadRmse(r.time_s, team_slack, m->payload_rmse_from_s)) continue;
    sum_sq += (r.x_true.segment<3>(Index::kPayloadPos) - r.reference.p_WL_W).cwiseAbs2();
    ++samples;
  }
  m->payload_rmse_m = samples > 0 ? Eigen::Vector3d((sum_sq / samples).cwiseSqrt())
                                  : Eigen::Vector3d::Constant(NAN);
  const double end_s = rows.back().time_s;
  int retauts = 0, failures = 0;
  for (int i = 0; i < vehicles; ++i) {
    VehicleMetrics& vm = m->vehicles[static_cast<size_t>(i)];
    for (const auto& [start, end] : SlackIntervals(times_s, modes[static_cast<size_t>(i)])) {
      vm.slack_time_s += end - start;
      ++vm.slack_events;
      vm.retaut_count += end < end_s ? 1 : 0;  // slack to the end never came taut again
    }
    vm.solve_ms = ComputeQuantiles(solve_ms[static_cast<size_t>(i)]);
    vm.mixer_saturated_fraction = rate_steps[static_cast<size_t>(i)] > 0
                                      ? static_cast<double>(saturated[static_cast<size_t>(i)]) /
                                            rate_steps[static_cast<size_t>(i)]
                                      : 0.0;
    retauts += vm.retaut_count;
    failures += vm.control_failures;
  }
  m->retaut_count = retauts;
  m->mpc_failures = failures;
  m->mpc_solve_ms = ComputeQuantiles(all_solve_ms);
  int all_steps = 0, all_saturated = 0;
  for (int i = 0; i < vehicles; ++i) {
    all_steps += rate_steps[static_cast<size_t>(i)];
    all_saturated += saturated[static_cast<size_t>(i)];
  }
  m->mixer_saturated_fraction =
      all_steps > 0 ? static_cast<double>(all_saturated) / all_steps : 0.0;
}

// Each fault event's recovery, as the single vehicle's (FaultRecoveries) on the payload's truth
// and reference and on the faulted vehicle's own state as its flight code saw it: with onboard
// estimation its filter's error and counts are measured, on motion capture they are null.
std::vector<FaultRecovery> TeamFaultRecoveries(const std::vector<TeamLogRow>& team_rows,
                                               const std::vector<FaultWindow>& windows,
                                               bool onboard) {
  std::vector<FaultRecovery> recoveries(windows.size());
  std::vector<LogRow> rows(team_rows.size());
  std::vector<bool> done(windows.size(), false);
  for (size_t first = 0; first < windows.size(); ++first) {
    if (done[first]) continue;
    // the rows of this window's vehicle, computed once for every window on that vehicle
    const int vehicle = windows[first].vehicle;
    for (size_t i = 0; i < team_rows.size(); ++i) {
      const TeamLogRow& in = team_rows[i];
      const TeamLogRow::Vehicle& v = in.vehicles[static_cast<size_t>(vehicle)];
      LogRow& row = rows[i];
      row.time_s = in.time_s;
      row.truth.p_WL_W = in.x_true.segment<3>(Index::kPayloadPos);
      row.truth.p_WQ_W = in.x_true.segment<3>(Index::Vehicle(vehicle) + Index::kVehiclePos);
      row.reference = in.reference;
      row.estimate = row.truth;
      row.estimate.p_WQ_W = v.p_WQ_seen_W;
      row.estimator_rejected_updates = v.estimator_rejected_updates;
      row.estimator_resets = v.estimator_resets;
    }
    // the spans need every window; a window's entry is the one computed on its vehicle's rows
    const std::vector<FaultRecovery> on_vehicle =
        FaultRecoveries(rows, windows, /*ground_truth=*/!onboard);
    for (size_t k = first; k < windows.size(); ++k) {
      if (windows[k].vehicle != vehicle) continue;
      recoveries[k] = on_vehicle[k];
      done[k] = true;
      if (!onboard) {
        recoveries[k].estimator_resets.reset();
        recoveries[k].rejected_updates.reset();
      }
    }
  }
  return recoveries;
}

// Each vehicle's payload-camera record into its metrics, and the team's: frames, detections and
// the share of frames with the payload in view over every vehicle's, the render, image-model
// and detector times over every rendered frame.
void TeamCameraMetrics(const std::vector<runner::VehicleCameraCounts>& counts, Metrics* m) {
  int frames = 0, in_view = 0;
  std::vector<double> render_ms, image_model_ms, detector_ms;
  m->detections = 0;
  for (size_t i = 0; i < counts.size(); ++i) {
    const runner::VehicleCameraCounts& c = counts[i];
    VehicleMetrics& v = m->vehicles[i];
    v.camera_frames = c.frames;
    if (c.frames > 0) {
      v.payload_in_fov_fraction = static_cast<double>(c.payload_in_view_frames) / c.frames;
    }
    frames += c.frames;
    in_view += c.payload_in_view_frames;
    m->detections += c.found_frames;
    render_ms.insert(render_ms.end(), c.render_ms.begin(), c.render_ms.end());
    image_model_ms.insert(image_model_ms.end(), c.image_model_ms.begin(), c.image_model_ms.end());
    detector_ms.insert(detector_ms.end(), c.detector_ms.begin(), c.detector_ms.end());
  }
  m->camera_frames = frames;
  if (frames > 0) m->payload_in_fov_fraction = static_cast<double>(in_view) / frames;
  m->render_ms = ComputeQuantiles(render_ms);
  m->image_model_ms = ComputeQuantiles(image_model_ms);
  m->detector_ms = ComputeQuantiles(detector_ms);
  m->team->cameras = true;
}

}  // namespace

RunResult RunTeamScenario(const Scenario& scenario, const Params& base_params,
                          const RunOptions& options) {
  // the team's controllers run on the simulation's thread (options.control_thread is the single
  // vehicle's); what needs the single vehicle's world is refused
  if (options.stop_at_s || options.at_stop) {
    throw InputError(scenario.file, "vehicles",
                     "a team scenario has no render-frame yet (docs/cooperative.md)");
  }
  const Params params = ScenarioParams(scenario, base_params);
  const Clock::time_point wall_start = Clock::now();
  RunResult result;
  Metrics& metrics = result.metrics;
  metrics.scenario = scenario.name;
  metrics.camera = scenario.estimation.ground_truth ? "ground_truth" : "mocap";
  metrics.seed = scenario.seed;
  metrics.world_profile = scenario.world.name;
  metrics.payload_rmse_from_s = RmseFromS(scenario.reference);
  const int n = static_cast<int>(scenario.team.vehicles.size());
  metrics.team = TeamMetrics();
  metrics.vehicles.resize(static_cast<size_t>(n));

  const CooperativeTeam team = TeamOf(scenario, params);
  const CooperativeModel model(team);
  const std::shared_ptr<const Reference> reference = MakeReference(scenario, params);
  sim::TeamWorldConfig world_config;
  world_config.team = team;
  world_config.seed = scenario.seed;
  world_config.gl_backend = options.gl_backend;  // the video's cameras (the physics never renders)
  // each vehicle's own IMU, VIO and rate gyro, as the single vehicle's world makes them, when its
  // flight code estimates its own state from them
  world_config.rates = ScenarioRates(scenario);
  world_config.profile = scenario.world;
  world_config.onboard_sensors =
      !scenario.estimation.ground_truth && scenario.estimation.vehicle_state == "onboard";
  const Eigen::VectorXd x0 =
      StartState(scenario, model, reference->At(0.0).p_WL_W, params.payload_radius_m);
  CheckStart(scenario, team, x0);
  auto world = std::make_unique<sim::TeamWorld>(world_config);
  // the world starts on its own cables: the profile's mismatch draws their lengths
  world->Reset(StartState(scenario, CooperativeModel(world->team()), reference->At(0.0).p_WL_W,
                          params.payload_radius_m));

  std::unique_ptr<runner::TeamFlightLink> flight;
  if (options.flight_stack.empty()) {
    flight = runner::MakeInProcessTeamFlight(scenario.controller.type, team, reference);
  } else {
    runner::ExternalTeamFlightOptions external;
    external.command = options.flight_stack;
    external.per_vehicle = options.team_stack_per_vehicle;
    external.step_timeout_s = options.flight_step_timeout_s;
    external.scenario = scenario.name;
    external.seed = scenario.seed;
    external.controller = scenario.controller.type;
    external.reference = scenario.reference;
    try {
      flight = runner::StartExternalTeamFlight(team, external);
    } catch (const std::exception& e) {
      // a separate flight stack that did not start: a run error, nothing flown
      metrics.flight_stack = "external";
      metrics.controller = "external";
      metrics.run_error = e.what();
      return result;
    }
  }
  metrics.flight_stack = flight->name();
  metrics.controller = flight->controller();
  runner::TeamRunLoop loop(scenario, params, options, std::move(world), reference,
                           std::move(flight), &result);
  loop.Run();
  loop.Finish();
  metrics.team->onboard = loop.onboard();
  ComputeTeamMetrics(result.team_rows, n, loop.rate_steps(), loop.saturated_steps(), &metrics);
  if (loop.cameras() != nullptr) TeamCameraMetrics(loop.cameras()->counts(), &metrics);
  metrics.faults = TeamFaultRecoveries(
      result.team_rows, FaultWindows(scenario.events, metrics.sim_time_s), loop.onboard());
  metrics.wall_time_s = std::chrono::duration<double>(Clock::now() - wall_start).count();
  CheckExpectations(scenario.expect, &metrics);
  return result;
}

}  // namespace hpa
