// The lockstep loop of one team run: events, motion capture, each vehicle's control step and
// rate loop, the video and the world's step, tick by tick on the physics clock.

#include "scenarios/src/runner/team_run_loop.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "hpa/controller/team_controller.h"
#include "hpa/models/cooperative_model.h"
#include "scenarios/src/runner/events/fault_event.h"

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
  metrics->team->payload_tilt_max_deg = std::max(
      metrics->team->payload_tilt_max_deg, TiltDeg(truth.x.segment<4>(Index::kPayloadQuat)));
}

TeamRunLoop::TeamRunLoop(const Scenario& scenario, const Params& params,
                         const RunOptions& options, std::unique_ptr<sim::TeamWorld> world,
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

  const size_t n = static_cast<size_t>(n_);
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
  clock_.BeginTick();
  if (clock_.Fires(control_loop_)) ControlStep(t);
  if (clock_.Fires(rate_loop_)) RateLoopStep();
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
  }
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
    const std::optional<sim::BodyReading>& own = latest_[static_cast<size_t>(i) + 1];
    if (!own || !payload) continue;
    TeamView& view = views[static_cast<size_t>(i)].emplace();
    view.time_s = t;
    view.p_WQ_W = own->p_W_m;
    view.v_WQ_W = own->v_W_mps;
    view.q_WB = own->q_W;
    view.w_B = scenario_.estimation.ground_truth ? own->w_body_radps : world_->GyroSample_B(i);
    view.p_WL_W = payload->p_W_m;
    view.v_WL_W = payload->v_W_mps;
    view.q_WP = payload->q_W;
    view.w_P = payload->w_body_radps;
  }
  const std::vector<std::optional<TeamReply>> replies = flight_->Step(views);
  for (size_t k = 0; k < static_cast<size_t>(n_); ++k) {
    TeamLogRow::Vehicle& v = last_[k];
    if (replies[k]) {
      command_[k] = replies[k]->output.command;
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

// Each vehicle's autopilot on its own rate gyro, towards its last command.
void TeamRunLoop::RateLoopStep() {
  for (int i = 0; i < n_; ++i) {
    const size_t k = static_cast<size_t>(i);
    if (!command_[k]) continue;
    const AutopilotOutput out = autopilots_[k]->Update(*command_[k], world_->GyroSample_B(i));
    world_->SetMotorSpeedCommand(i, out.w_cmd_radps);
    last_[k].mixer_saturated = out.saturated;
    ++rate_steps_[k];
    saturated_[k] += out.saturated ? 1 : 0;
  }
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
