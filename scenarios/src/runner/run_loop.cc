#include "scenarios/src/runner/run_loop.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "hpa/estimator/estimator_registry.h"
#include "hpa/models/camera_model.h"
#include "hpa/models/input_error.h"
#include "hpa/models/seed_streams.h"

namespace hpa::runner {
namespace {

double Ms(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// How far the payload's image may move between two rendered frames and stay in the region
// around its last detection (beyond it the whole frame is rendered and searched).
constexpr double kRegionMarginPx = 48.0;

}  // namespace

SystemState InitialState(const Reference& reference, const Params& params) {
  SystemState s;
  const ReferencePoint r = reference.At(0.0);
  s.p_WL_W = r.p_WL_W;
  s.p_WQ_W = r.p_WL_W + Eigen::Vector3d(0, 0, params.cable_length_m);
  s.mode = CableMode::kTaut;
  return s;
}

void CheckReferenceAboveGround(const Reference& reference, double duration_s,
                               const Params& params) {
  for (double t_s = 0.0; t_s <= duration_s + 1e-9; t_s += 0.01) {
    const ReferencePoint r = reference.At(t_s);
    if (!(r.p_WL_W.z() >= params.payload_radius_m)) {
      std::ostringstream what;
      what.precision(4);
      what << "the payload reference is " << r.p_WL_W.z() << " m high at t = " << t_s
           << " s: below the ground (the payload's radius, " << params.payload_radius_m
           << " m, is the lowest it can be)";
      throw InputError("", "reference", what.str());
    }
  }
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
      render_camera_(scenario.estimation.camera == "render"),
      camera_rng_(DeriveSeed(scenario.seed, SeedStream::kAnalyticCamera)) {
  // the world: flight params plus the scenario's world-only overrides
  sim::WorldConfig world_config;
  world_config.params = params;
  world_config.overrides.payload_mass_kg = scenario.world_payload_mass_kg;
  world_config.overrides.cable_length_m = scenario.world_cable_length_m;
  world_config.seed = scenario.seed;
  world_config.rates = ScenarioRates(scenario);
  world_config.profile = scenario.world;
  world_config.gl_backend = options.gl_backend;
  world_config.randomize_appearance = scenario.estimation.camera_randomize;
  const RateTable rates = world_config.rates;
  world_ = std::make_unique<sim::World>(world_config);

  // flight code: reference, controller, rate loop, estimator (flight params only); the world
  // starts from its own parameters (mismatch draw and overrides)
  reference_ = MakeReference(scenario, params);
  CheckReferenceAboveGround(*reference_, scenario.duration_s, params);
  world_->Reset(InitialState(*reference_, world_->world_params()));
  controller_ = MakeController(scenario.controller, params, reference_);
  rate_controller_ = std::make_unique<BodyRateController>(params);
  // the profile may fly PX4's rate loop instead, on the world's rate gyro
  if (scenario.rate_loop.px4) {
    px4_rate_ = std::make_unique<Px4RateController>(params, scenario.rate_loop.params);
  }
  EstimatorConfig estimator_config;
  estimator_config.tension_cue.enabled = scenario.estimation.slack_tension_cue;
  estimator_ = MakeEstimator(EstimatorOf(scenario), estimator_config, params,
                             InitialState(*reference_, params));
  detector_ = std::make_unique<PayloadDetector>(params);
  CameraNoiseModel camera_noise = MeasuredDetectorNoise();
  camera_noise.centre_std_px *= scenario.estimation.detector_noise_scale;
  camera_noise.semi_major_std_px *= scenario.estimation.detector_noise_scale;
  analytic_camera_ = std::make_unique<sim::AnalyticCamera>(params, camera_noise);

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
  camera_loop_ = clock_->AddLoop("camera", rates.camera.rate_hz);
  control_loop_ = clock_->AddLoop("control", controller_->RateHz());
  rate_loop_ = px4_rate_ ? -1 : clock_->AddLoop("rate", rates.imu.rate_hz);
  video_loop_ = video_rate_hz > 0.0 ? clock_->AddLoop("video", video_rate_hz) : -1;
  rate_loop_dt_s_ = 1.0 / rates.imu.rate_hz;
  events_ = scenario.events;
  std::stable_sort(events_.begin(), events_.end(),
                   [](const EventSpec& a, const EventSpec& b) { return a.at_s < b.at_s; });

  // latencies: the camera's capture to detection; of the flight code (world profile): a command
  // reaches the rate loop compute + transport after the state it was computed from, and the
  // controller reads an estimate that is estimate_s old
  const sim::LatencyProfile& latency = scenario.world.latency;
  detections_in_flight_ = std::make_unique<DelayLine<PayloadDetection>>(rates.camera.latency_s);
  commands_in_flight_ =
      std::make_unique<DelayLine<ControlOutput>>(latency.compute_s + latency.transport_s);
  delayed_estimate_ = latency.estimate_s > 0.0;
  estimates_in_flight_ = std::make_unique<DelayLine<SystemState>>(latency.estimate_s);
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

  // which loops run at this tick; truth and the flight state only when one needs them
  clock_->BeginTick();
  const bool camera_due = clock_->Fires(camera_loop_);
  const bool control_due = clock_->Fires(control_loop_);
  const bool rate_due = rate_loop_ >= 0 && clock_->Fires(rate_loop_);
  const bool video_due = video_loop_ >= 0 && clock_->Fires(video_loop_);
  const bool need_state = control_due || rate_due || video_due || delayed_estimate_;
  sim::Truth truth;
  if (camera_due || control_due || video_due || (ground_truth_ && need_state)) {
    truth = world_->GetTruth();
  }

  if (camera_due) CameraStep(t, truth);
  while (auto detection = detections_in_flight_->PopReady(t)) {
    estimator_->OnPayloadDetection(*detection);
  }

  // what flight code sees
  SystemState state;
  if (need_state) state = ground_truth_ ? truth.state : estimator_->Estimate(t);
  state.time_s = t;
  const SystemState controller_state = ControllerState(t, state);
  if (control_due) ControlStep(t, truth, state, controller_state);
  while (auto arrived = commands_in_flight_->PopReady(t)) control_ = *arrived;
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

// The payload camera: capture now, deliver after the latency.
void RunLoop::CameraStep(double t, const sim::Truth& truth) {
  const Eigen::Vector3d p_CL_C = PayloadInCamera_C(params_, truth.state);
  CameraFrameRecord frame;
  frame.time_s = t;
  frame.payload_in_image = InsideImage(params_, p_CL_C);
  if (!ground_truth_) {
    const PayloadDetection detection = render_camera_
                                           ? RenderAndDetect(t, &frame)
                                           : analytic_camera_->Measure(p_CL_C, t, camera_rng_);
    frame.detected = detection.found;
    detections_in_flight_->Push(detection.time_s, detection);
  }
  for (RunRecorder* r : recorders_) r->OnCameraFrame(frame);
}

// The region around the last detection first; the whole frame when the region cannot decide
// (DetectInRegion's result equals the whole frame's when it gives one). Recorders never change
// this path: a video renders frames of its own.
PayloadDetection RunLoop::RenderAndDetect(double t, CameraFrameRecord* frame) {
  const cv::Rect region = detector_->RegionAround(last_detection_, kRegionMarginPx);
  // renders `area` (empty: the whole frame) and detects in it; times add up
  const auto render_and_detect = [&](const cv::Rect& area) {
    world_->RenderPayloadCamera(&rendered_, area);
    frame->render_ms += world_->last_camera_timing().render_ms;
    frame->image_model_ms += world_->last_camera_timing().image_model_ms;
    const auto r1 = Clock::now();
    const std::optional<PayloadDetection> d =
        area.area() > 0 ? detector_->DetectInRegion(rendered_, area, t)
                        : std::optional<PayloadDetection>(detector_->Detect(rendered_, t));
    frame->detector_ms += Ms(r1, Clock::now());
    return d;
  };
  std::optional<PayloadDetection> in_region;
  if (region.area() > 0) in_region = render_and_detect(region);
  frame->region_only = in_region.has_value();
  const PayloadDetection detection = in_region ? *in_region : *render_and_detect(cv::Rect());
  last_detection_ = detection;
  frame->frame = &rendered_;
  return detection;
}

// The estimate the controller may read: now, or estimate_s ago (labelled with the time it is
// read: the controller does not know its age).
SystemState RunLoop::ControllerState(double t, const SystemState& state) {
  SystemState controller_state = state;
  if (delayed_estimate_) {
    estimates_in_flight_->Push(t, state);
    while (auto old = estimates_in_flight_->PopReady(t)) {
      delayed_state_ = *old;
      have_delayed_state_ = true;
    }
    if (have_delayed_state_) controller_state = delayed_state_;
    controller_state.time_s = t;
  }
  return controller_state;
}

// The high-level controller; its command reaches the rate loop after compute + transport.
void RunLoop::ControlStep(double t, const sim::Truth& truth, const SystemState& state,
                          const SystemState& controller_state) {
  const ControlOutput computed = controller_->Update(controller_state);
  commands_in_flight_->Push(t, computed);
  LogRow row;
  row.time_s = t;
  row.truth = truth.state;
  row.estimate = state;
  row.reference = reference_->At(t);
  row.command = computed.command;
  row.status = computed.status;
  row.solve_time_ms = computed.solve_time_ms;
  row.cost = computed.cost;
  row.cable_tension_N = truth.cable_tension_N;
  row.gripper_active = world_->gripper_active();
  row.mixer_saturated = mixer_saturated_;
  if (!ground_truth_) {
    const EstimatorHealth health = estimator_->Health();
    row.estimator_rejected_updates = health.RejectedUpdates();
    row.estimator_resets = health.ForcedAccepts();
  }
  for (RunRecorder* r : recorders_) r->OnControlStep(row);
}

// The body-rate loop: PX4's runs on each new sample of its gyro (none yet at the first tick: the
// motors keep the world's initial hover command). The estimator is told the thrust the
// allocation made (a saturated mixer lowers it).
void RunLoop::RateLoopStep(const SystemState& state, bool rate_due) {
  if (px4_rate_) {
    if (const std::optional<GyroSample> gyro = world_->TakeRateGyro()) {
      world_->SetMotorSpeedCommand(px4_rate_->Update(control_.command, gyro->gyro_B_radps));
      const Px4RateStatus& mixer = px4_rate_->status();
      if (!ground_truth_) estimator_->OnAllocatedThrust(mixer.thrust_allocated_N);
      ++inputs_.rate_loop_steps;
      inputs_.mixer_saturated_steps += mixer.saturated ? 1 : 0;
      mixer_saturated_ = mixer.saturated;
    }
  } else if (rate_due) {
    const InputVector w_cmd =
        rate_controller_->Update(control_.command, state.w_B, rate_loop_dt_s_);
    world_->SetMotorSpeedCommand(w_cmd);
    const double allocated_N = params_.k_f_N_per_radps2 * w_cmd.squaredNorm();
    if (!ground_truth_) estimator_->OnAllocatedThrust(allocated_N);
    ++inputs_.rate_loop_steps;
    mixer_saturated_ = allocated_N < control_.command.thrust_N - 1e-6;
    inputs_.mixer_saturated_steps += mixer_saturated_ ? 1 : 0;
  }
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

// One physics step, the sensors to the estimator (with ground truth its output is never read:
// drain only), then the crash check.
bool RunLoop::StepWorld() {
  world_->Step();
  while (auto imu = world_->TakeImu()) {
    if (!ground_truth_) estimator_->OnImu(*imu);
  }
  while (auto vio = world_->TakeVio()) {
    if (!ground_truth_) estimator_->OnVio(*vio);
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
  if (!ground_truth_) {
    metrics.estimator = EstimatorOf(scenario_);
    metrics.estimator_health = estimator_->Health().Fields();
  }
  metrics.sim_time_s = std::min(tick_, end_tick_) * sim::World::kPhysicsDt_s;
  metrics.payload_quad_min_distance_m = world_->payload_quad_min_distance_m();
  const sim::ContactCounts& contacts = world_->contact_counts();
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
