#include "hpa/scenarios/runner.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <deque>
#include <random>

#include "hpa/controller/body_rate_controller.h"
#include "hpa/estimator/analytic_camera.h"
#include "hpa/estimator/estimator.h"
#include "hpa/estimator/estimator_registry.h"
#include "hpa/estimator/payload_detector.h"
#include "hpa/models/camera_model.h"
#include "hpa/scenarios/video_recorder.h"
#include "hpa/sim/world.h"

namespace hpa {
namespace {

using Clock = std::chrono::steady_clock;

constexpr int kImuDecimation = 2;       // 500 Hz body-rate loop on the 1 kHz physics clock
constexpr double kCameraRateHz = 30.0;  // payload camera and detector
constexpr double kVideoRateHz = 30.0;

double Ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// The initial state: payload at the reference's start, hanging at rest under the quadrotor,
// with the cable length of `params` (the world's for the world, the flight code's for the
// estimator: a world-only override must not reach flight code through its initial state).
SystemState InitialState(const Reference& reference, const Params& params) {
  SystemState s;
  const ReferencePoint r = reference.At(0.0);
  s.p_WL_W = r.p_WL_W;
  s.p_WQ_W = r.p_WL_W + Eigen::Vector3d(0, 0, params.cable_length_m);
  s.mode = CableMode::kTaut;
  return s;
}

// Ticks (1 ms) at which event k of a rate_hz clock fires.
long TickOf(long k, double rate_hz) {
  return static_cast<long>(std::llround(k * 1000.0 / rate_hz));
}

}  // namespace

namespace {
volatile std::sig_atomic_t g_stop_signal = 0;  // set from a signal handler
}  // namespace

void RequestStop(int signal_number) { g_stop_signal = signal_number; }

Params WorldParams(const Scenario& scenario, const Params& params) {
  Params p = params;
  if (scenario.world_payload_mass_kg) p.payload_mass_kg = *scenario.world_payload_mass_kg;
  if (scenario.world_cable_length_m) p.cable_length_m = *scenario.world_cable_length_m;
  return p;
}

RunResult RunScenario(const Scenario& scenario, const Params& params, const RunOptions& options) {
  const auto wall_start = Clock::now();
  RunResult result;
  Metrics& metrics = result.metrics;
  metrics.scenario = scenario.name;
  metrics.controller = scenario.controller.type;
  metrics.camera = scenario.estimation.ground_truth ? "ground_truth" : scenario.estimation.camera;
  metrics.seed = scenario.seed;

  // the world: flight params plus the scenario's world-only overrides
  sim::WorldConfig world_config;
  world_config.params = params;
  world_config.overrides.payload_mass_kg = scenario.world_payload_mass_kg;
  world_config.overrides.cable_length_m = scenario.world_cable_length_m;
  world_config.seed = scenario.seed;
  sim::World world(world_config);

  // flight code: reference, controller, rate loop, estimator (flight params only)
  const std::shared_ptr<const Reference> reference = MakeReference(scenario, params);
  world.Reset(InitialState(*reference, WorldParams(scenario, params)));
  std::unique_ptr<Controller> controller = MakeController(scenario.controller, params, reference);
  BodyRateController rate_controller(params);
  EstimatorConfig estimator_config;
  estimator_config.tension_cue.enabled = scenario.estimation.slack_tension_cue;
  std::unique_ptr<Estimator> estimator = MakeEstimator(EstimatorOf(scenario), estimator_config,
                                                       params, InitialState(*reference, params));
  const bool ground_truth = scenario.estimation.ground_truth;
  const bool render_camera = scenario.estimation.camera == "render";
  PayloadDetector detector(params);
  CameraNoiseModel camera_noise = MeasuredDetectorNoise();
  camera_noise.centre_std_px *= scenario.estimation.detector_noise_scale;
  camera_noise.semi_major_std_px *= scenario.estimation.detector_noise_scale;
  AnalyticCamera analytic_camera(params, camera_noise);
  std::mt19937_64 camera_rng(scenario.seed * 0x9E3779B97F4A7C15ULL + 17);

  std::unique_ptr<VideoRecorder> video;
  if (!options.video_path.empty()) {
    video = std::make_unique<VideoRecorder>(options.video_path, kVideoRateHz,
                                            options.video_slack_events_only);
  }

  // lockstep schedule on the 1 kHz physics clock
  const double end_s = std::min(scenario.duration_s, options.stop_at_s.value_or(1e300));
  const long end_tick = static_cast<long>(std::llround(end_s / sim::World::kPhysicsDt_s));
  const double control_rate_hz = controller->RateHz();
  long next_control = 0, next_camera = 0, next_video = 0;
  size_t next_event = 0;
  std::vector<EventSpec> events = scenario.events;
  std::stable_sort(events.begin(), events.end(),
                   [](const EventSpec& a, const EventSpec& b) { return a.at_s < b.at_s; });
  std::deque<PayloadDetection> in_flight;  // detections waiting out the camera latency
  MetricsInputs inputs;
  ControlOutput control;
  control.command.thrust_N = params.HoverThrustN();
  cv::Mat last_onboard_frame;
  const bool show_progress = options.progress && isatty(STDERR_FILENO);
  int last_progress_pct = -1;

  long tick = 0;
  try {
    for (; tick <= end_tick; ++tick) {
      const double t = tick * sim::World::kPhysicsDt_s;
      if (g_stop_signal != 0) {
        throw std::runtime_error("stopped by signal " + std::to_string(g_stop_signal));
      }

      // scripted disturbances
      while (next_event < events.size() && events[next_event].at_s <= t + 1e-9) {
        ApplyEvent(events[next_event++], &world);
      }

      // which loops run at this tick; truth and the flight state only when one needs them
      const bool camera_due = tick == TickOf(next_camera, kCameraRateHz);
      const bool control_due = tick == TickOf(next_control, control_rate_hz);
      const bool rate_due = tick % kImuDecimation == 0;
      const bool video_due = video && tick == TickOf(next_video, kVideoRateHz);
      const bool need_state = control_due || rate_due || video_due;
      sim::Truth truth;
      if (camera_due || control_due || video_due || (ground_truth && rate_due)) {
        truth = world.GetTruth();
      }

      // payload camera: capture now, deliver after the latency
      if (camera_due) {
        ++next_camera;
        const Eigen::Vector3d p_CL_C = PayloadInCamera_C(params, truth.state);
        inputs.payload_in_fov_per_frame.push_back(InsideImage(params, p_CL_C));
        if (!ground_truth) {
          PayloadDetection detection;
          if (render_camera) {
            const auto r0 = Clock::now();
            last_onboard_frame = world.RenderPayloadCamera();
            const auto r1 = Clock::now();
            detection = detector.Detect(last_onboard_frame, t);
            inputs.render_ms.push_back(Ms(r0, r1));
            inputs.detector_ms.push_back(Ms(r1, Clock::now()));
          } else {
            detection = analytic_camera.Measure(p_CL_C, t, camera_rng);
          }
          if (detection.found) ++inputs.detections;
          in_flight.push_back(detection);
        }
      }
      while (!in_flight.empty() &&
             in_flight.front().time_s + scenario.estimation.camera_latency_s <= t + 1e-9) {
        estimator->OnPayloadDetection(in_flight.front());
        in_flight.pop_front();
      }

      // what flight code sees
      SystemState state;
      if (need_state) state = ground_truth ? truth.state : estimator->Estimate(t);
      state.time_s = t;

      // high-level controller
      if (control_due) {
        ++next_control;
        control = controller->Update(state);
        LogRow row;
        row.time_s = t;
        row.truth = truth.state;
        row.estimate = state;
        row.reference = reference->At(t);
        row.command = control.command;
        row.status = control.status;
        row.solve_time_ms = control.solve_time_ms;
        row.cost = control.cost;
        row.cable_tension_N = truth.cable_tension_N;
        row.gripper_active = world.gripper_active();
        if (!ground_truth) {
          const EstimatorHealth health = estimator->Health();
          row.estimator_rejected_updates = health.RejectedUpdates();
          row.estimator_resets = health.ForcedAccepts();
        }
        result.rows.push_back(row);
      }

      // body-rate loop
      if (rate_due) {
        const InputVector w_cmd = rate_controller.Update(control.command, state.w_B,
                                                         kImuDecimation * sim::World::kPhysicsDt_s);
        world.SetMotorSpeedCommand(w_cmd);
        if (!ground_truth) estimator->OnThrustCommand(control.command.thrust_N);
      }

      // video frame
      if (video_due) {
        ++next_video;
        if (last_onboard_frame.empty() || ground_truth || !render_camera) {
          last_onboard_frame = world.RenderPayloadCamera();
        }
        VideoRecorder::Hud hud{t, truth.state.mode, state.mode, control.command.thrust_N,
                               truth.cable_tension_N};
        video->AddFrame(world.RenderChaseCamera(VideoRecorder::kWidthPx, VideoRecorder::kHeightPx),
                        last_onboard_frame, hud);
      }

      if (tick == end_tick) break;
      world.Step();
      // sensors to the estimator (with ground truth its output is never read: drain only)
      while (auto imu = world.TakeImu()) {
        if (!ground_truth) estimator->OnImu(*imu);
      }
      while (auto vio = world.TakeVio()) {
        if (!ground_truth) estimator->OnVio(*vio);
      }

      const sim::CrashStatus crash = world.Crash();
      if (crash.crashed) {
        metrics.crashed = true;
        metrics.crash_time_s = crash.time_s;
        metrics.crash_reason = crash.reason;
        break;
      }
      if (show_progress) {
        const int pct = static_cast<int>(100.0 * tick / end_tick);
        if (pct != last_progress_pct) {
          last_progress_pct = pct;
          const double wall_s = Ms(wall_start, Clock::now()) / 1000.0;
          std::fprintf(stderr, "\r%s: %3d%%  t = %6.2f / %.2f s  (%.2f sim s per wall s)",
                       scenario.name.c_str(), pct, t, end_s, t / std::max(wall_s, 1e-9));
        }
      }
    }
    if (options.at_stop) options.at_stop(world);
  } catch (const std::exception& e) {
    // keep what was computed: the metrics of the run so far, with the error named
    metrics.run_error = std::string(e.what()) +
                        " (at t = " + std::to_string(tick * sim::World::kPhysicsDt_s) + " s)";
  }
  if (show_progress) std::fprintf(stderr, "\n");
  if (video) video->Finish();

  if (!ground_truth) {
    metrics.estimator = EstimatorOf(scenario);
    metrics.estimator_health = estimator->Health().Fields();
  }
  metrics.sim_time_s = std::min(tick, end_tick) * sim::World::kPhysicsDt_s;
  inputs.rows = std::move(result.rows);
  ComputeMetrics(inputs, &metrics);
  result.rows = std::move(inputs.rows);
  CheckExpectations(scenario.expect, &metrics);
  metrics.wall_time_s = Ms(wall_start, Clock::now()) / 1000.0;
  return result;
}

}  // namespace hpa
