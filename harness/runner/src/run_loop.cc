// RunLoop's frame: its setup from the scenario (the world, the flight stack, the autopilot, the
// recorders, the lockstep schedule, the events and the latencies), the tick and its order of
// steps (run_loop_steps.cc holds the steps), the progress line and the end of the run with its
// metrics; and the runner's own log recorder.
#include "harness/runner/src/run_loop.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>

#include "hpa/models/camera_model.h"
#include "hpa/models/seed_streams.h"
#include "harness/runner/src/events/fault_event.h"

namespace hpa::runner {
namespace {

double Ms(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// The options of a flight stack run as a separate process: its command, its frame ring (a
// rendered camera's frames), the scenario's rate table and its rate loop.
ExternalFlightOptions ExternalOptionsOf(const Scenario& scenario, const Params& params,
                                        const RunOptions& options, const RateTable& rates,
                                        bool camera_frames) {
  ExternalFlightOptions external;
  external.command = options.flight_stack;
  external.step_timeout_s = options.flight_step_timeout_s;
  external.scenario = scenario.name;
  external.seed = scenario.seed;
  if (camera_frames) {
    // frames in flight at once (capture to delivery), one being written, one spare
    // two per frame (its region of interest and the whole frame)
    external.frames.slots =
        2 * (static_cast<int>(std::ceil(rates.camera.latency_s * rates.camera.rate_hz)) + 2);
    external.frames.width_px = params.camera_width_px;
    external.frames.height_px = params.camera_height_px;
  }
  nlohmann::json rate_rows = nlohmann::json::array();
  for (const RateRow& r : ScenarioRateTable(scenario, params)) {
    rate_rows.push_back({{"name", r.name}, {"rate_hz", r.rate_hz}, {"latency_s", r.latency_s}});
  }
  external.rates = rate_rows;
  external.rate_loop = {scenario.rate_loop, rates.imu.rate_hz};  // MakeAutopilot's (RunLoop)
  return external;
}

// Sizes the log and the camera's records once: one log row per control step (a stack that
// commands faster than it says only makes the log grow) and one record per camera frame.
void ReserveInputs(const Scenario& scenario, const RateTable& rates, double control_rate_hz,
                   bool render_camera, MetricsInputs* inputs) {
  if (std::isfinite(control_rate_hz) && control_rate_hz > 0.0 &&
      control_rate_hz <= rates.physics_hz) {
    inputs->rows.reserve(static_cast<size_t>(std::ceil(scenario.duration_s * control_rate_hz)) + 2);
  }
  const size_t frames =
      static_cast<size_t>(std::ceil(scenario.duration_s * rates.camera.rate_hz)) + 2;
  inputs->payload_in_fov_per_frame.reserve(frames);
  if (render_camera) {
    inputs->render_ms.reserve(frames);
    inputs->image_model_ms.reserve(frames);
    inputs->detector_ms.reserve(frames);
  }
}

// An implausible event is flown as written, but said once at run start (the world's params,
// which the event's plausibility depends on, are known only now).
void WarnImplausibleEvents(const Scenario& scenario, const Params& world_params) {
  for (size_t i = 0; i < scenario.events.size(); ++i) {
    const EventSpec& event = scenario.events[i];
    if (!event.action) continue;
    const std::string warning = event.action->Warning(world_params);
    if (warning.empty()) continue;
    std::fprintf(stderr, "warning: %s: events.%zu (%s at %g s): %s\n", scenario.name.c_str(), i,
                 event.type.c_str(), event.at_s, warning.c_str());
  }
}

}  // namespace

void LogRecorder::OnCameraFrame(const CameraFrameRecord& frame) {
  inputs_->payload_in_fov_per_frame.push_back(frame.payload_in_image);
  if (frame.frame != nullptr) {
    inputs_->render_ms.push_back(frame.render_ms);
    inputs_->image_model_ms.push_back(frame.image_model_ms);
    inputs_->detector_ms.push_back(frame.detector_ms);
    inputs_->region_frames += frame.region_only ? 1 : 0;
  }
  if (frame.detected) ++inputs_->detections;
}

RunLoop::RunLoop(const Scenario& scenario, const Params& params, const RunOptions& options,
                 Metrics* metrics)
    : scenario_(scenario),
      params_(params),
      options_(options),
      metrics_(metrics),
      wall_start_(Clock::now()),
      ground_truth_(scenario.estimation.ground_truth),
      render_camera_(scenario.estimation.camera == "render") {
  // the world: flight params plus the scenario's world-only overrides
  const sim::WorldConfig world_config = WorldConfigOf(scenario, params, options.gl_backend);
  const RateTable rates = world_config.rates;
  world_ = std::make_unique<sim::World>(world_config);

  // flight code: the flight stack (detector, estimator, controller; flight params only), in
  // process or as a separate process, and the rate loop; the world starts from its own
  // parameters (mismatch draw and overrides)
  reference_ = MakeReference(scenario, params);
  CheckFlyable(*reference_, scenario, params);
  CheckFlyable(*reference_, scenario, world_->world_params());
  world_->Reset(InitialState(*reference_, world_->world_params()));
  flight::FlightConfig flight_config =
      FlightConfigOf(scenario, params, InitialState(*reference_, params));
  flight_config.control_thread = options.control_thread && options.flight_stack.empty();
  if (options.flight_stack.empty()) {
    flight_ = MakeInProcessFlight(flight_config);
  } else {
    flight_ = StartExternalFlight(
        flight_config,
        ExternalOptionsOf(scenario, params, options, rates, render_camera_ && !ground_truth_));
  }
  metrics->flight_stack = flight_->name();
  metrics->controller = flight_->controller();  // what flies: a separate stack names its own
  // a separate stack that uses no pixels flies without the rendered camera: no frame is rendered
  // or sent for it, and what the camera would count is null (metrics.json's camera "none")
  if (render_camera_ && !ground_truth_ && !flight_->uses_pixels()) {
    render_camera_ = false;
    metrics->camera = "none";
    metrics->camera_flown = false;
  }
  // one log row per control step and one record per camera frame, sized once
  ReserveInputs(scenario, rates, flight_->control_rate_hz(), render_camera_, &inputs_);
  // the scenario's autopilot (the profile's rate loop): PX4's runs on the world's rate gyro; a
  // stack that owns the rate loop runs it on its side, on the same schedule and inputs
  autopilot_ = MakeAutopilot(params, scenario.rate_loop, rates.imu.rate_hz);

  // recorders: the log and metrics inputs, then the caller's (a video among them)
  recorders_.push_back(&log_recorder_);
  recorders_.insert(recorders_.end(), options.recorders.begin(), options.recorders.end());
  double video_rate_hz = 0.0;
  for (const RunRecorder* r : options.recorders)
    video_rate_hz = std::max(video_rate_hz, r->video_rate_hz());

  // lockstep schedule on the physics clock
  end_s_ = std::min(scenario.duration_s, options.stop_at_s.value_or(1e300));
  end_tick_ = static_cast<long>(std::llround(end_s_ / sim::World::kPhysicsDt_s));
  clock_ = std::make_unique<LockstepClock>(rates.physics_hz);
  rate_loop_ = autopilot_->RunsOnGyro() ? -1 : clock_->AddLoop("rate", rates.imu.rate_hz);
  video_loop_ = video_rate_hz > 0.0 ? clock_->AddLoop("video", video_rate_hz) : -1;
  WarnImplausibleEvents(scenario, world_->world_params());
  events_ = scenario.events;
  std::stable_sort(events_.begin(), events_.end(),
                   [](const EventSpec& a, const EventSpec& b) { return a.at_s < b.at_s; });
  inputs_.faults = FaultWindows(scenario.events, end_s_);  // their recovery metrics
  inputs_.ground_truth = ground_truth_;

  // latencies: the world delivers each sensor's messages (the camera's among them) after the
  // latency it declares; a command reaches the rate loop compute + transport after the state it
  // was computed from (world profile); the estimate's own latency is the flight stack's
  const sim::LatencyProfile& latency = scenario.world.latency;
  commands_in_flight_ =
      std::make_unique<DelayLine<CommandInFlight>>(latency.compute_s + latency.transport_s);
  control_.command.thrust_N = params.HoverThrustN();
  show_progress_ = options.progress && isatty(STDERR_FILENO);
}

void RunLoop::Run() {
  for (; tick_ <= end_tick_; ++tick_, clock_->Advance()) {
    if (!Tick()) break;
  }
  if (options_.at_stop) options_.at_stop(*world_);
}

bool RunLoop::Tick() {
  const double t = tick_ * sim::World::kPhysicsDt_s;
  if (StopSignal() != 0) {
    throw std::runtime_error("stopped by signal " + std::to_string(StopSignal()));
  }
  ApplyDueEvents(t);

  // which loops run at this tick; truth only when something needs it
  clock_->BeginTick();
  const bool rate_due = rate_loop_ >= 0 && clock_->Fires(rate_loop_);
  const bool video_due = video_loop_ >= 0 && clock_->Fires(video_loop_);
  sim::Truth truth;
  bool have_truth = false;
  const auto need_truth = [&] {
    if (!have_truth) truth = world_->GetTruth();
    have_truth = true;
  };
  if (video_due || ground_truth_) need_truth();
  CameraStep();

  // the flight stack's tick: this tick's messages in, its estimate and command out
  pending_.time_s = t;
  pending_.need_estimate = rate_due || video_due;
  if (ground_truth_) pending_.truth = truth.state;
  if (flight_->wants_reference()) {
    const ReferencePoint r = reference_->At(t);
    pending_.reference = {r.p_WL_W, r.v_WL_W, r.a_WL_W};
  }
  const flight::FlightOutputs out = flight_->Step(pending_);
  pending_.Clear();  // the lists keep their storage from tick to tick
  inputs_.detections += out.frames_detected;
  stack_roi_ = out.camera_roi;  // the region of its next frame
  SystemState state = out.estimate;
  state.time_s = t;
  if (out.has_command) {
    need_truth();
    ControlStep(t, truth, state, out);
  }
  while (auto arrived = commands_in_flight_->PopReady(t)) control_ = TakeCommand(&*arrived);
  RateLoopStep(state, rate_due);
  if (video_due) VideoStep(t, truth, state);

  if (tick_ == end_tick_) return false;
  if (!StepWorld()) return false;
  if (show_progress_) ShowProgress(t);
  return true;
}

void RunLoop::ApplyDueEvents(double t) {
  while (next_event_ < events_.size() && events_[next_event_].at_s <= t + 1e-9) {
    ApplyEvent(events_[next_event_++], world_.get());
  }
}

void RunLoop::ShowProgress(double t) {
  const int pct = static_cast<int>(100.0 * tick_ / end_tick_);
  if (pct == last_progress_pct_) return;
  last_progress_pct_ = pct;
  const double wall_s = Ms(wall_start_, Clock::now()) / 1000.0;
  std::fprintf(stderr, "\r%s: %3d%%  t = %6.2f / %.2f s  (%.2f sim s per wall s)",
               scenario_.name.c_str(), pct, t, end_s_, t / std::max(wall_s, 1e-9));
}

void RunLoop::Finish(RunResult* result) {
  if (show_progress_) std::fprintf(stderr, "\n");
  Metrics& metrics = *metrics_;
  // the flight stack's end: the last step's sensors, the frames still in flight (detected, not
  // delivered) and its estimator's health
  for (sim::SensorMessage& m : world_->TakeInFlight()) KeepTickStartMessage(&m);
  for (CameraFrame& f : camera_frames_) pending_.frames.push_back(std::move(f));
  // the commands still on the control thread: computed and logged, as the run computed them
  while (!rows_awaiting_command_.empty()) {
    LogRow row = std::move(rows_awaiting_command_.front());
    rows_awaiting_command_.pop_front();
    try {
      AwaitPendingCommand(&row);
      for (RunRecorder* r : recorders_) r->OnControlStep(row);
    } catch (const std::exception& e) {
      const std::string what = std::string("at the end of the run: ") + e.what();
      metrics.run_error = metrics.run_error ? *metrics.run_error + "; " + what : what;
    }
  }
  try {
    const FlightFinish finish = flight_->Finish(pending_);
    if (!ground_truth_) {
      metrics.estimator = finish.estimator;
      metrics.estimator_health = finish.estimator_health;
    }
    inputs_.detections += finish.frames_detected;
  } catch (const std::exception& e) {
    const std::string what = std::string("at the end of the run: ") + e.what();
    metrics.run_error = metrics.run_error ? *metrics.run_error + "; " + what : what;
  }
  metrics.sim_time_s = std::min(tick_, end_tick_) * sim::World::kPhysicsDt_s;
  metrics.payload_quad_min_distance_m = world_->contacts().payload_quad_min_distance_m();
  const sim::ContactCounts& contacts = world_->contacts().counts();
  metrics.contacts_payload_body = contacts.payload_body;
  metrics.contacts_payload_rotor = contacts.payload_rotor;
  metrics.contacts_payload_ground = contacts.payload_ground;
  metrics.contacts_quad_ground = contacts.quad_ground;
  metrics.contacts_payload_gripper = contacts.payload_gripper;
  ComputeMetrics(inputs_, &metrics);
  if (!metrics.camera_flown) MarkUnmeasured(CameraNotFlownMetrics(), &metrics);
  result->rows = std::move(inputs_.rows);
  CheckExpectations(scenario_.expect, &metrics);
  metrics.wall_time_s = Ms(wall_start_, Clock::now()) / 1000.0;
}

}  // namespace hpa::runner
