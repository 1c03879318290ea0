// The lockstep loop of one team run: events, motion capture, each vehicle's control step and
// rate loop, the video and the world's step, tick by tick on the physics clock.

#include "harness/runner/src/team_run_loop.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>

#include "hpa/controller/team_controller.h"
#include "hpa/estimator/estimator.h"
#include "hpa/models/cooperative_model.h"
#include "harness/runner/src/events/fault_event.h"

namespace hpa::runner {
namespace {

using Index = CooperativeStateIndex;

// A body's pose and velocity from the team state (body -1: the payload).
sim::BodyReading ReadingFromState(const Eigen::VectorXd& x, int body, double time_s) {
  const int start = body < 0 ? 0 : Index::Vehicle(body);
  sim::BodyReading r;
  r.body = body;
  r.capture_time_s = time_s;
  r.p_W_m = x.segment<3>(start + Index::kVehiclePos);
  r.v_W_mps = x.segment<3>(start + Index::kVehicleVel);
  const Eigen::Vector4d q = x.segment<4>(start + Index::kVehicleQuat);
  r.q_W = Eigen::Quaterniond(q(0), q(1), q(2), q(3));
  r.w_body_radps = x.segment<3>(start + Index::kVehicleRate);
  return r;
}

}  // namespace

void UpdateTeamExtremes(const sim::TeamTruth& truth, Metrics* metrics) {
  for (size_t i = 0; i < metrics->vehicles.size(); ++i) {
    const int start = Index::Vehicle(static_cast<int>(i)) + Index::kVehicleQuat;
    UpdateVehicleExtremes(truth.x.segment<4>(start), truth.cable_tension_N[i],
                          &metrics->vehicles[i]);
  }
  metrics->team->payload_tilt_max_deg = std::max(metrics->team->payload_tilt_max_deg,
                                                 TiltDeg(truth.x.segment<4>(Index::kPayloadQuat)));
}

TeamRunLoop::TeamRunLoop(const Scenario& scenario, const Params& params, const RunOptions& options,
                         std::unique_ptr<sim::TeamWorld> world,
                         std::shared_ptr<const Reference> reference,
                         std::unique_ptr<TeamFlightLink> flight, RunResult* result)
    : scenario_(scenario),
      options_(options),
      result_(result),
      metrics_(result->metrics),
      wall_start_(Clock::now()),
      n_(world->VehicleCount()),
      world_(std::move(world)),
      reference_(std::move(reference)),
      flight_(std::move(flight)),
      clock_(1.0 / sim::World::kPhysicsDt_s) {
  // each vehicle's rate loop at the IMU rate, as the single vehicle's
  const double rate_loop_hz = RateTable().imu.rate_hz;
  for (int i = 0; i < n_; ++i) {
    autopilots_.push_back(MakeAutopilot(params, scenario.rate_loop, rate_loop_hz));
  }
  control_loop_ = clock_.AddLoop("control", flight_->RateHz());
  rate_loop_ = clock_.AddLoop("rate loop", rate_loop_hz);
  double video_rate_hz = 0.0;
  for (const RunRecorder* r : options.recorders) {
    video_rate_hz = std::max(video_rate_hz, r->video_rate_hz());
  }
  video_loop_ = video_rate_hz > 0.0 ? clock_.AddLoop("video", video_rate_hz) : -1;
  if (scenario.team.payload_cameras) {
    // each vehicle's payload camera: rendered from the world's mounts, detected with the flight
    // code's numbers (the team's params)
    CooperativeTeam flight_team = world_->team();
    for (CooperativeVehicle& v : flight_team.vehicles) v.params = params;
    TeamCameraConfig camera;
    camera.kind = scenario.estimation.camera == "render" ? sim::CameraKind::kRendered
                                                         : sim::CameraKind::kAnalytic;
    camera.rate = ScenarioRates(scenario).camera;
    camera.seed = scenario.seed;
    camera.detector_noise_scale = scenario.estimation.detector_noise_scale;
    cameras_ = std::make_unique<TeamPayloadCameras>(flight_team, scenario.world, camera);
    camera_loop_ = clock_.AddLoop("camera", camera.rate.rate_hz);
  }

  const size_t n = static_cast<size_t>(n_);
  if (world_->onboard_sensors()) {
    // each vehicle's filter starts at its known start, as the single vehicle's estimator does
    world_->GetTruth(&truth_);
    for (int i = 0; i < n_; ++i) {
      const int at = Index::Vehicle(i);
      QuadFilterState start;
      start.time_s = world_->time_s();
      start.p_WB_W = truth_.x.segment<3>(at + Index::kVehiclePos);
      start.v_WB_W = truth_.x.segment<3>(at + Index::kVehicleVel);
      const Eigen::Vector4d q = truth_.x.segment<4>(at + Index::kVehicleQuat);
      start.q_WB = Eigen::Quaterniond(q(0), q(1), q(2), q(3)).normalized();
      filters_.emplace_back(params, QuadFilterConfig(), start);
    }
    rate_gyro_.resize(n);
  }
  // the profile's latencies, as the single vehicle's run loop and flight stack apply them
  const sim::LatencyProfile& latency = scenario.world.latency;
  if (latency.compute_s + latency.transport_s > 0.0) {
    commands_in_flight_.assign(n,
                               DelayLine<BodyRateCommand>(latency.compute_s + latency.transport_s));
  }
  if (latency.estimate_s > 0.0) {
    own_in_flight_.assign(n, DelayLine<TeamView>(latency.estimate_s));
    own_arrived_.resize(n);
  }
  latest_.resize(n + 1);
  command_.resize(n);
  last_.resize(n);
  rate_steps_.assign(n, 0);
  saturated_.assign(n, 0);
  min_separation_m_ = world_->MinVehicleSeparation_m();
  end_tick_ = std::lround(scenario.duration_s / sim::World::kPhysicsDt_s);
  show_progress_ = options.progress && isatty(STDERR_FILENO);
}

void TeamRunLoop::Run() {
  try {
    for (tick_ = 0; tick_ <= end_tick_; ++tick_, clock_.Advance()) {
      if (!Tick()) break;
    }
    flight_->Finish();
  } catch (const std::exception& e) {
    // keep what was computed: the metrics of the run so far, with the error named
    metrics_.run_error =
        std::string(e.what()) + " (at t = " + std::to_string(world_->time_s()) + " s)";
  }
  if (show_progress_) std::fprintf(stderr, "\n");
}

bool TeamRunLoop::Tick() {
  const double t = clock_.time_s();
  if (StopRequested() != 0) {
    throw std::runtime_error("stopped by signal " + std::to_string(StopRequested()));
  }
  ApplyDueEvents(t);
  ReadBodies(t);
  if (!own_in_flight_.empty()) DelayOwnStates(t);
  clock_.BeginTick();
  if (cameras_) CameraStep(t);
  if (clock_.Fires(control_loop_)) ControlStep(t);
  if (!commands_in_flight_.empty()) DeliverCommands(t);
  if (onboard() && autopilots_.front()->RunsOnGyro()) {
    // PX4's loop on each new sample of the vehicle's own rate gyro, as the single vehicle's
    for (int i = 0; i < n_; ++i) {
      if (const std::optional<GyroSample> gyro =
              std::exchange(rate_gyro_[static_cast<size_t>(i)], std::nullopt)) {
        FlyRateLoop(i, gyro->gyro_B_radps);
      }
    }
  } else if (clock_.Fires(rate_loop_)) {
    RateLoopStep();
  }
  if (video_loop_ >= 0 && clock_.Fires(video_loop_)) VideoStep();
  if (tick_ == end_tick_) return false;
  if (!StepWorld()) return false;
  if (show_progress_) ShowProgress(t);
  return true;
}

// Each event due by now acts on the body or the vehicle it names.
void TeamRunLoop::ApplyDueEvents(double t) {
  const std::vector<EventSpec>& events = scenario_.events;
  while (next_event_ < events.size() && events[next_event_].at_s <= t + 1e-9) {
    const EventAction* action = events[next_event_++].action.get();
    if (const auto* e = dynamic_cast<const ImpulseEvent*>(action)) {
      world_->ApplyImpulse(e->on_payload ? -1 : e->vehicle.value_or(0), e->impulse_W_Ns,
                           e->duration_s);
    } else if (const auto* v = dynamic_cast<const VelocityChangeEvent*>(action)) {
      world_->AddVelocity(v->on_payload ? -1 : v->vehicle.value_or(0), v->dv_W_mps);
    } else if (const auto* f = dynamic_cast<const FaultEvent*>(action)) {
      world_->faults(f->vehicle.value_or(0)).Inject(f->At(world_->time_s()));
    }
  }
}

// This tick's truth (the extremes over the log's span), then what the flight code holds of each
// body: the truth with the ground-truth switch, else the motion capture delivered by now.
void TeamRunLoop::ReadBodies(double t) {
  world_->GetTruth(&truth_);
  if (!result_->team_rows.empty()) UpdateTeamExtremes(truth_, &metrics_);
  if (scenario_.estimation.ground_truth) {
    for (int body = -1; body < n_; ++body) {
      latest_[static_cast<size_t>(body + 1)] = ReadingFromState(truth_.x, body, t);
    }
  } else {
    world_->TakeDelivered(&delivered_);
    for (sim::BodyReading& r : delivered_) latest_[static_cast<size_t>(r.body + 1)] = r;
    if (onboard()) OnboardStep();
  }
}

void TeamRunLoop::OnboardStep() {
  for (int i = 0; i < n_; ++i) {
    VehicleFilter& filter = filters_[static_cast<size_t>(i)];
    world_->TakeDelivered(i, &sensor_messages_);
    for (const sim::SensorMessage& m : sensor_messages_) {
      if (const auto* imu = std::get_if<ImuSample>(&m)) filter.OnImu(*imu);
      if (const auto* vio = std::get_if<VioSample>(&m)) filter.OnVio(*vio);
      if (const auto* gyro = std::get_if<GyroSample>(&m)) {
        rate_gyro_[static_cast<size_t>(i)] = *gyro;  // the newest counts
      }
    }
  }
}

// Each vehicle's own state as it is now goes into its estimate latency; the newest whose
// latency has passed is what its flight code reads (the single vehicle's FlightStack does the
// same with its estimate).
void TeamRunLoop::DelayOwnStates(double t) {
  for (int i = 0; i < n_; ++i) {
    const size_t k = static_cast<size_t>(i);
    TeamView own;
    if (OwnState(i, t, &own)) own_in_flight_[k].Push(t, own);
    while (std::optional<TeamView> old = own_in_flight_[k].PopReady(t)) own_arrived_[k] = *old;
  }
}

// Each vehicle's camera frame when one is due (of the tick's state, before its step, as the
// single vehicle's camera), and the detections whose latency has passed taken off its queue (a
// team controller does not read them: the payload's state is motion capture's).
void TeamRunLoop::CameraStep(double t) {
  if (clock_.Fires(camera_loop_)) cameras_->Capture(*world_, t);
  for (int i = 0; i < n_; ++i) cameras_->TakeDelivered(i, t, &detections_);
}

// The commands whose compute and transport latency has passed reach their rate loops.
void TeamRunLoop::DeliverCommands(double t) {
  for (size_t k = 0; k < commands_in_flight_.size(); ++k) {
    while (std::optional<BodyRateCommand> c = commands_in_flight_[k].PopReady(t)) command_[k] = *c;
  }
}

// Vehicle i's own state in its view: its filter's estimate (onboard), else its own reading
// (motion capture or the truth, body rate from its gyro on motion capture); false while it has
// none yet.
bool TeamRunLoop::OwnState(int i, double t, TeamView* view) const {
  if (onboard()) {
    const QuadFilterState e =
        filters_[static_cast<size_t>(i)].Estimate(t, EstimatorConfig().max_extrapolation_s);
    view->p_WQ_W = e.p_WB_W;
    view->v_WQ_W = e.v_WB_W;
    view->q_WB = e.q_WB;
    view->w_B = e.w_B_radps;
    return true;
  }
  const std::optional<sim::BodyReading>& own = latest_[static_cast<size_t>(i) + 1];
  if (!own) return false;
  view->p_WQ_W = own->p_W_m;
  view->v_WQ_W = own->v_W_mps;
  view->q_WB = own->q_W;
  view->w_B = scenario_.estimation.ground_truth ? own->w_body_radps : world_->GyroSample_B(i);
  return true;
}

// Each vehicle's view (its own readings and the payload's, nothing of another vehicle's) to its
// flight code, its reply into its command and log columns, and a log row once every vehicle has
// flown a command (the first readings take the motion-capture latency to arrive; until then the
// motors hold the start's hover).
void TeamRunLoop::ControlStep(double t) {
  TeamLogRow row;
  row.time_s = t;
  row.x_true = truth_.x;
  row.reference = reference_->At(t);
  std::vector<std::optional<TeamView>> views(static_cast<size_t>(n_));
  const std::optional<sim::BodyReading>& payload = latest_[0];
  for (int i = 0; i < n_; ++i) {
    TeamView own;
    if (!payload || !OwnState(i, t, &own)) continue;
    // with an estimate latency: the newest state that has arrived (now's until the first has)
    if (!own_arrived_.empty() && own_arrived_[static_cast<size_t>(i)]) {
      own = *own_arrived_[static_cast<size_t>(i)];
    }
    TeamView& view = views[static_cast<size_t>(i)].emplace(own);
    view.time_s = t;
    view.p_WL_W = payload->p_W_m;
    view.v_WL_W = payload->v_W_mps;
    view.q_WP = payload->q_W;
    view.w_P = payload->w_body_radps;
  }
  const std::vector<std::optional<TeamReply>> replies = flight_->Step(views);
  for (size_t k = 0; k < static_cast<size_t>(n_); ++k) {
    TeamLogRow::Vehicle& v = last_[k];
    if (views[k]) v.p_WQ_seen_W = views[k]->p_WQ_W;
    if (onboard()) {
      const FilterCounts& counts = filters_[k].counts();
      v.estimator_rejected_updates = counts.rejected_updates;
      v.estimator_resets = counts.forced_accepts + filters_[k].restarts();
    }
    if (replies[k]) {
      if (commands_in_flight_.empty()) {
        command_[k] = replies[k]->output.command;
      } else {
        commands_in_flight_[k].Push(t, replies[k]->output.command);
      }
      v.command = replies[k]->output.command;
      v.status = replies[k]->output.status;
      v.solve_time_ms = replies[k]->output.solve_time_ms;
      v.taut_seen = replies[k]->cable_taut;
    }
    v.cable_length_m = truth_.cable_length_m[k];
    v.cable_tension_N = truth_.cable_tension_N[k];
    v.mode = truth_.modes[k];
  }
  if (std::all_of(command_.begin(), command_.end(), [](const auto& c) { return c.has_value(); })) {
    row.vehicles = last_;
    result_->team_rows.push_back(std::move(row));
  }
}

// Each vehicle's autopilot towards its last command, on its body rate: its filter's estimate
// (onboard, as the single vehicle's own rate loop), else its motion-capture world's gyro.
void TeamRunLoop::RateLoopStep() {
  for (int i = 0; i < n_; ++i) {
    if (onboard()) {
      const double t = world_->time_s();
      FlyRateLoop(i, filters_[static_cast<size_t>(i)]
                         .Estimate(t, EstimatorConfig().max_extrapolation_s)
                         .w_B_radps);
    } else {
      FlyRateLoop(i, world_->GyroSample_B(i));
    }
  }
}

void TeamRunLoop::FlyRateLoop(int i, const Eigen::Vector3d& w_B_radps) {
  const size_t k = static_cast<size_t>(i);
  if (!command_[k]) return;
  const AutopilotOutput out = autopilots_[k]->Update(*command_[k], w_B_radps);
  world_->SetMotorSpeedCommand(i, out.w_cmd_radps);
  last_[k].mixer_saturated = out.saturated;
  ++rate_steps_[k];
  saturated_[k] += out.saturated ? 1 : 0;
}

void TeamRunLoop::VideoStep() {
  const std::vector<TeamLogRow>& rows = result_->team_rows;
  const TeamLogRow* latest_row = rows.empty() ? nullptr : &rows.back();
  for (RunRecorder* r : options_.recorders) r->OnTeamVideoTick(*world_, latest_row);
}

bool TeamRunLoop::StepWorld() {
  world_->Step();
  min_separation_m_ = std::min(min_separation_m_, world_->MinVehicleSeparation_m());
  return !world_->Crash().crashed;
}

void TeamRunLoop::ShowProgress(double t) {
  const int pct = static_cast<int>(100.0 * tick_ / std::max(end_tick_, 1L));
  if (pct == last_progress_pct_) return;
  last_progress_pct_ = pct;
  const double wall_s = std::chrono::duration<double>(Clock::now() - wall_start_).count();
  std::fprintf(stderr, "\r%s: %3d%%  t = %6.2f / %.2f s  (%.2f sim s per wall s)",
               scenario_.name.c_str(), pct, t, scenario_.duration_s, t / std::max(wall_s, 1e-9));
}

void TeamRunLoop::Finish() {
  // the last step's state (a crash ends the loop before its tick reads it)
  world_->GetTruth(&truth_);
  if (!result_->team_rows.empty()) UpdateTeamExtremes(truth_, &metrics_);
  const sim::CrashStatus crash = world_->Crash();
  metrics_.crashed = crash.crashed;
  if (crash.crashed) {
    metrics_.crash_time_s = crash.time_s;
    metrics_.crash_reason = crash.reason;
  }
  metrics_.sim_time_s = world_->time_s();
  metrics_.team->min_vehicle_separation_m = min_separation_m_;
}

}  // namespace hpa::runner
