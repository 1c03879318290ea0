#include "scenarios/src/runner/run_loop.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "hpa/models/camera_model.h"
#include "hpa/models/input_error.h"
#include "hpa/models/seed_streams.h"
#include "scenarios/src/runner/events/fault_event.h"

namespace hpa::runner {
namespace {

double Ms(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// An attitude as the (w, x, y, z) vector TiltDeg reads.
Eigen::Vector4d Wxyz(const Eigen::Quaterniond& q) { return {q.w(), q.x(), q.y(), q.z()}; }

}  // namespace

SystemState InitialState(const Reference& reference, const Params& params) {
  SystemState s;
  const ReferencePoint r = reference.At(0.0);
  s.p_WL_W = r.p_WL_W;
  s.p_WQ_W = r.p_WL_W + Eigen::Vector3d(0, 0, params.cable_length_m);
  s.mode = CableMode::kTaut;
  return s;
}

namespace {

// "0.7" with up to 4 significant digits, for messages.
std::string Num(double v) {
  std::ostringstream out;
  out.precision(4);
  out << v;
  return out.str();
}

}  // namespace

void CheckFlyable(const Reference& reference, const Scenario& scenario, const Params& params) {
  const double duration_s = scenario.duration_s;
  const std::string& file = scenario.file;
  // hover within the motors' range: full thrust at least 1.25 x the weight (hover at most 80 %
  // of it, leaving a fifth to steer with: a quadrotor at its thrust limit cannot also tilt),
  // and the idle thrust below the weight (else it cannot descend)
  const double weight_N = (params.quad_mass_kg + params.payload_mass_kg) * params.gravity_mps2;
  const double thrust_max_N = 4.0 * params.RotorThrustMaxN();
  const double thrust_idle_N = 4.0 * params.RotorThrustMinN();
  constexpr double kHoverFractionMax = 0.8;
  if (!(weight_N <= kHoverFractionMax * thrust_max_N)) {
    throw InputError(file, "params",
                     "cannot hover: quadrotor and payload weigh " + Num(weight_N) +
                         " N and the four rotors give at most " + Num(thrust_max_N) +
                         " N (4 k_f w_max^2); hover must take at most 80 % of full thrust "
                         "(raise rotor.k_f_N_per_radps2 or rotor.motor_speed_max_radps, or lower "
                         "the masses or gravity_mps2)");
  }
  if (!(thrust_idle_N < kHoverFractionMax * weight_N)) {
    throw InputError(file, "params.rotor.motor_speed_min_radps",
                     "the idle thrust " + Num(thrust_idle_N) + " N is not below 80 % of the " +
                         Num(weight_N) + " N weight: the vehicle could not descend");
  }
  // geometry: the payload hangs clear of the body, and the vehicle fits in the arena
  const Eigen::Vector3d& half_B_m = params.body_half_size_m;
  if (!(params.cable_length_m > params.payload_radius_m + half_B_m.z())) {
    throw InputError(file, "params.cable.length_m",
                     "a cable of " + Num(params.cable_length_m) + " m hangs a payload of radius " +
                         Num(params.payload_radius_m) + " m into the body (half height " +
                         Num(half_B_m.z()) + " m)");
  }
  if (!(std::max(half_B_m.x(), half_B_m.y()) < 0.5 * sim::kArenaHalfWidth_m)) {
    throw InputError(file, "params.quadrotor.body_half_size_m",
                     "a body " + Num(2 * half_B_m.x()) + " x " + Num(2 * half_B_m.y()) +
                         " m wide does not fly in a " + Num(2 * sim::kArenaHalfWidth_m) +
                         " m arena");
  }
  // the reference over the whole run: the payload above the ground, the vehicle hanging above
  // it inside the arena (body included)
  for (double t_s = 0.0; t_s <= duration_s + 1e-9; t_s += 0.01) {
    const ReferencePoint r = reference.At(t_s);
    const Eigen::Vector3d p_WL_W = r.p_WL_W;
    const Eigen::Vector3d p_WQ_W = p_WL_W + Eigen::Vector3d(0, 0, params.cable_length_m);
    const std::string at = " at t = " + Num(t_s) + " s";
    if (!p_WL_W.allFinite()) throw InputError(file, "reference", "not finite" + at);
    if (!(p_WL_W.z() >= params.payload_radius_m)) {
      throw InputError(file, "reference",
                       "the payload reference is " + Num(p_WL_W.z()) + " m high" + at +
                           ": below the ground (the payload's radius, " +
                           Num(params.payload_radius_m) + " m, is the lowest it can be)");
    }
    const bool inside = std::abs(p_WQ_W.x()) + half_B_m.x() <= sim::kArenaHalfWidth_m &&
                        std::abs(p_WQ_W.y()) + half_B_m.y() <= sim::kArenaHalfWidth_m &&
                        p_WQ_W.z() + half_B_m.z() <= sim::kArenaHeight_m;
    if (!inside) {
      throw InputError(
          file, "reference",
          "puts the payload at (" + Num(p_WL_W.x()) + ", " + Num(p_WL_W.y()) + ", " +
              Num(p_WL_W.z()) + ") m" + at + ": the vehicle, " + Num(params.cable_length_m) +
              " m above it, would be outside the " + Num(2 * sim::kArenaHalfWidth_m) + " x " +
              Num(2 * sim::kArenaHalfWidth_m) + " x " + Num(sim::kArenaHeight_m) + " m arena");
    }
  }
}

}  // namespace hpa::runner

namespace hpa {

sim::WorldConfig WorldConfigOf(const Scenario& scenario, const Params& params,
                               sim::GlBackend gl_backend) {
  sim::WorldConfig world_config;
  world_config.params = params;
  world_config.overrides.payload_mass_kg = scenario.world_payload_mass_kg;
  world_config.overrides.cable_length_m = scenario.world_cable_length_m;
  world_config.seed = scenario.seed;
  world_config.rates = ScenarioRates(scenario);
  world_config.profile = scenario.world;
  world_config.gl_backend = gl_backend;
  world_config.randomize_appearance = scenario.estimation.camera_randomize;
  world_config.camera.kind = scenario.estimation.ground_truth         ? sim::CameraKind::kNone
                             : scenario.estimation.camera == "render" ? sim::CameraKind::kRendered
                                                                      : sim::CameraKind::kAnalytic;
  world_config.camera.detector_noise_scale = scenario.estimation.detector_noise_scale;
  return world_config;
}

}  // namespace hpa

namespace hpa::runner {

flight::FlightConfig FlightConfigOf(const Scenario& scenario, const Params& params,
                                    const SystemState& initial) {
  flight::FlightConfig c;
  c.params = params;
  c.controller = scenario.controller;
  c.estimator = EstimatorOf(scenario);
  c.slack_tension_cue = scenario.estimation.slack_tension_cue;
  c.reference = scenario.reference;
  c.ground_truth = scenario.estimation.ground_truth;
  c.estimate_latency_s = scenario.world.latency.estimate_s;
  c.tick_hz = 1.0 / sim::World::kPhysicsDt_s;
  c.initial_state = initial;
  return c;
}

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
    ExternalFlightOptions external;
    external.command = options.flight_stack;
    external.step_timeout_s = options.flight_step_timeout_s;
    external.scenario = scenario.name;
    external.seed = scenario.seed;
    if (render_camera_ && !ground_truth_) {
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
    external.rate_loop = {scenario.rate_loop, rates.imu.rate_hz};  // MakeAutopilot's, below
    flight_ = StartExternalFlight(flight_config, external);
  }
  metrics->flight_stack = flight_->name();
  metrics->controller = flight_->controller();  // what flies: a separate stack names its own
  // one log row per control step: sized once (a stack that commands faster than it says only
  // makes the log grow)
  const double control_rate_hz = flight_->control_rate_hz();
  if (std::isfinite(control_rate_hz) && control_rate_hz > 0.0 &&
      control_rate_hz <= rates.physics_hz) {
    inputs_.rows.reserve(static_cast<size_t>(std::ceil(scenario.duration_s * control_rate_hz)) + 2);
  }
  // and one record per camera frame
  const size_t frames =
      static_cast<size_t>(std::ceil(scenario.duration_s * rates.camera.rate_hz)) + 2;
  inputs_.payload_in_fov_per_frame.reserve(frames);
  if (render_camera_) {
    inputs_.render_ms.reserve(frames);
    inputs_.image_model_ms.reserve(frames);
    inputs_.detector_ms.reserve(frames);
  }
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
  // an implausible event is flown as written, but said once at run start (the world's params,
  // which the event's plausibility depends on, are known only now)
  for (size_t i = 0; i < scenario.events.size(); ++i) {
    const EventSpec& event = scenario.events[i];
    if (!event.action) continue;
    const std::string warning = event.action->Warning(world_->world_params());
    if (warning.empty()) continue;
    std::fprintf(stderr, "warning: %s: events.%zu (%s at %g s): %s\n", scenario.name.c_str(), i,
                 event.type.c_str(), event.at_s, warning.c_str());
  }
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

// The payload camera: the world captures it if due (its message delivered after its latency),
// a rendered frame read out by the flight stack in the region it asked for; then the camera's
// messages delivered by now join this tick's inputs.
void RunLoop::CameraStep() {
  cv::Rect region;
  if (render_camera_ && world_->CameraFrameDue()) {
    region = flight_->detects_at_capture() ? flight_->CaptureRegion() : stack_roi_;
  }
  if (std::optional<sim::CameraCapture> capture = world_->CaptureTickStart(region)) {
    if (capture->exposure) ReadOutExposure(&*capture);
    for (RunRecorder* r : recorders_) r->OnCameraFrame(*capture);
  }
  // the gripper's switch, and a camera without latency, deliver at their capture tick
  world_->TakeDelivered(&delivered_);
  for (sim::SensorMessage& m : delivered_) KeepTickStartMessage(&m);
  for (PayloadDetection& d : camera_detections_) pending_.detections.push_back(std::move(d));
  for (CameraFrame& f : camera_frames_) pending_.frames.push_back(std::move(f));
  camera_detections_.clear();
  camera_frames_.clear();
}

// The flight stack reads a rendered exposure out: it detects at capture (in its region first,
// the whole frame only when it asks), or it receives the region and the whole frame in its
// frame ring; what it made of the frame is the camera's message.
void RunLoop::ReadOutExposure(sim::CameraCapture* capture) {
  sim::CameraExposure& exposure = *capture->exposure;
  if (flight_->detects_at_capture()) {
    // the whole frame's render time is not the detector's
    double whole_read_ms = 0.0;
    const WholeFrameReader read_whole = [&]() -> const cv::Mat& {
      const Clock::time_point render_start = Clock::now();
      const cv::Mat& whole = exposure.ReadWhole();
      whole_read_ms += Ms(render_start, Clock::now());
      return whole;
    };
    const Clock::time_point detect_start = Clock::now();
    PayloadDetection detection = flight_->DetectCaptured(exposure.frame(), read_whole);
    capture->detector_ms = Ms(detect_start, Clock::now()) - whole_read_ms;
    capture->detected = detection.found;
    world_->QueueCameraMessage(std::move(detection));
  } else {
    CameraFrame frames;
    frames.capture_time_s = exposure.frame().capture_time_s;
    const cv::Rect& roi = exposure.frame().region;
    if (roi.area() > 0) {
      cv::Mat* region = flight_->NextFrameSlot(&frames.region_slot);
      exposure.frame().region_bgr(roi).copyTo((*region)(roi));
      frames.region = roi;
      frames.region_bgr = *region;
    }
    cv::Mat* whole = flight_->NextFrameSlot(&frames.whole_slot);
    exposure.ReadWhole().copyTo(*whole);
    frames.whole_bgr = *whole;
    world_->QueueCameraMessage(std::move(frames));
  }
  capture->region_only = !exposure.whole_read();
  capture->frame = &exposure.pixels();
  capture->render_ms = exposure.render_ms();
  capture->image_model_ms = exposure.image_model_ms();
}

// Keeps a delivered camera message for the flight stack's next tick (the gripper's switch for
// this one).
void RunLoop::KeepTickStartMessage(sim::SensorMessage* message) {
  if (auto* g = std::get_if<GripperSample>(message)) pending_.gripper_active = g->active;
  if (auto* d = std::get_if<PayloadDetection>(message)) camera_detections_.push_back(std::move(*d));
  if (auto* f = std::get_if<CameraFrame>(message)) camera_frames_.push_back(std::move(*f));
}

namespace {
// A log row's command fields.
void FillCommand(const ControlOutput& computed, LogRow* row) {
  row->command = computed.command;
  row->status = computed.status;
  row->solve_time_ms = computed.solve_time_ms;
  row->cost = computed.cost;
}
}  // namespace

// The flight stack's control step; its command reaches the rate loop after compute + transport
// (one computed on the control thread is logged then, when it is taken).
void RunLoop::ControlStep(double t, const sim::Truth& truth, const SystemState& state,
                          const flight::FlightOutputs& out) {
  if (!flown_) {
    // the log's span starts here: its first state counts towards the extremes
    flown_ = true;
    UpdateVehicleExtremes(Wxyz(truth.state.q_WB), truth.cable_tension_N,
                          &inputs_.extremes);
  }
  commands_in_flight_->Push(t, CommandInFlight{out.command, out.command_pending});
  LogRow row;
  row.time_s = t;
  row.truth = truth.state;
  row.estimate = state;
  row.reference = reference_->At(t);
  row.cable_tension_N = truth.cable_tension_N;
  row.gripper_active = world_->gripper().active();
  row.mixer_saturated = mixer_saturated_;
  if (!ground_truth_) {
    row.estimator_rejected_updates = out.estimator_rejected_updates;
    row.estimator_resets = out.estimator_resets;
    row.estimator_health_resets = out.estimator_health_resets;
  }
  if (out.command_pending) {
    rows_awaiting_command_.push_back(std::move(row));  // logged when its command is taken
    return;
  }
  FillCommand(out.command, &row);
  for (RunRecorder* r : recorders_) r->OnControlStep(row);
}

// A command reaching the rate loop: one computed on the control thread is taken now (waiting
// for it if need be) and its log row, held until now, logged.
ControlOutput RunLoop::TakeCommand(CommandInFlight* command) {
  if (!command->pending) return std::move(command->output);
  LogRow row = std::move(rows_awaiting_command_.front());
  rows_awaiting_command_.pop_front();
  const ControlOutput output = AwaitPendingCommand(&row);  // a throw drops the row
  for (RunRecorder* r : recorders_) r->OnControlStep(row);
  return output;
}

// The oldest pending control step's command into its row, with the step's estimate and
// estimator health when they came with the command (a separate stack's batched ticks).
ControlOutput RunLoop::AwaitPendingCommand(LogRow* row) {
  const flight::FlightOutputs reply = flight_->AwaitReply();
  if (reply.has_estimate) {
    row->estimate = reply.estimate;
    row->estimate.time_s = row->time_s;
    if (!ground_truth_) {
      row->estimator_rejected_updates = reply.estimator_rejected_updates;
      row->estimator_resets = reply.estimator_resets;
      row->estimator_health_resets = reply.estimator_health_resets;
    }
  }
  FillCommand(reply.command, row);
  return reply.command;
}

// The body-rate loop: PX4's runs on each new sample of its gyro (none yet at the first tick: the
// motors keep the world's initial hover command); the scenario's autopilot runs it, or the
// flight stack when it owns the rate loop. The estimator is told the thrust the allocation made
// (a saturated mixer lowers it).
void RunLoop::RateLoopStep(const SystemState& state, bool rate_due) {
  std::optional<Eigen::Vector3d> w_B_radps;
  if (autopilot_->RunsOnGyro()) {
    if (const std::optional<GyroSample> gyro = std::exchange(rate_gyro_, std::nullopt)) {
      w_B_radps = gyro->gyro_B_radps;
    }
  } else if (rate_due) {
    w_B_radps = state.w_B;
  }
  if (!w_B_radps) return;
  const AutopilotOutput out =
      flight_->owns_rate_loop()
          ? flight_->RateLoop(flight::RateTick{state.time_s, control_.command, *w_B_radps})
          : autopilot_->Update(control_.command, *w_B_radps);
  world_->SetMotorSpeedCommand(out.w_cmd_radps);
  pending_.allocation = flight::AllocationReport{out.thrust_allocated_N, out.saturated};
  ++inputs_.rate_loop_steps;
  inputs_.mixer_saturated_steps += out.saturated ? 1 : 0;
  mixer_saturated_ = out.saturated;
}

void RunLoop::VideoStep(double t, const sim::Truth& truth, const SystemState& state) {
  LogRow now;
  now.time_s = t;
  now.truth = truth.state;
  now.estimate = state;
  now.command = control_.command;
  now.cable_tension_N = truth.cable_tension_N;
  for (RunRecorder* r : recorders_) r->OnVideoTick(*world_, now, cv::Mat());
}

// One physics step, its sensor samples queued for the flight stack's next tick, then the crash
// check.
bool RunLoop::StepWorld() {
  world_->Step();
  if (flown_) {
    const sim::Truth truth = world_->GetTruth();
    UpdateVehicleExtremes(Wxyz(truth.state.q_WB), truth.cable_tension_N,
                          &inputs_.extremes);
  }
  world_->TakeDelivered(&delivered_);
  for (sim::SensorMessage& m : delivered_) {
    if (auto* imu = std::get_if<ImuSample>(&m)) pending_.imu.push_back(*imu);
    if (auto* vio = std::get_if<VioSample>(&m)) pending_.vio.push_back(*vio);
    if (auto* gyro = std::get_if<GyroSample>(&m)) rate_gyro_ = *gyro;  // the newest counts
    KeepTickStartMessage(&m);
  }
  const sim::CrashStatus crash = world_->Crash();
  if (!crash.crashed) return true;
  metrics_->crashed = true;
  metrics_->crash_time_s = crash.time_s;
  metrics_->crash_reason = crash.reason;
  return false;
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
  result->rows = std::move(inputs_.rows);
  CheckExpectations(scenario_.expect, &metrics);
  metrics.wall_time_s = Ms(wall_start_, Clock::now()) / 1000.0;
}

}  // namespace hpa::runner
