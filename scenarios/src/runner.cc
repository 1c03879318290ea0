#include "hpa/scenarios/runner.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <deque>
#include <random>
#include <sstream>

#include "hpa/controller/body_rate_controller.h"
#include "hpa/controller/px4_rate_controller.h"
#include "hpa/estimator/estimator.h"
#include "hpa/estimator/estimator_registry.h"
#include "hpa/estimator/payload_detector.h"
#include "hpa/models/camera_model.h"
#include "hpa/models/input_error.h"
#include "hpa/scenarios/video_recorder.h"
#include "hpa/sim/analytic_camera.h"
#include "hpa/sim/world.h"

namespace hpa {
namespace {

using Clock = std::chrono::steady_clock;

double Ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// How far the payload's image may move between two rendered frames and stay in the region
// around its last detection (beyond it the whole frame is rendered and searched).
constexpr double kRegionMarginPx = 48.0;

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

// A reference that puts the payload into the ground cannot be flown: refused before the run,
// naming the first time it does (every 10 ms of the run).
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

// The runner's own recorders: log rows and metrics inputs, and the video.
class LogRecorder final : public RunRecorder {
 public:
  explicit LogRecorder(MetricsInputs* inputs) : inputs_(inputs) {}
  void OnControlStep(const LogRow& row) override { inputs_->rows.push_back(row); }
  void OnCameraFrame(const CameraFrameRecord& frame) override {
    inputs_->payload_in_fov_per_frame.push_back(frame.payload_in_image);
    if (frame.frame != nullptr) {
      inputs_->render_ms.push_back(frame.render_ms);
      inputs_->image_model_ms.push_back(frame.image_model_ms);
      inputs_->detector_ms.push_back(frame.detector_ms);
      inputs_->region_frames += frame.region_only ? 1 : 0;
    }
    if (frame.detected) ++inputs_->detections;
  }

 private:
  MetricsInputs* inputs_;
};

// Records the video from its own renders: the chase camera and a whole onboard frame at each
// video tick. It never reads or changes what the loop's camera path uses (its region, its
// frames), so a run with a video is the run without one.
class VideoTickRecorder final : public RunRecorder {
 public:
  VideoTickRecorder(const std::string& path, double rate_hz, bool slack_events_only)
      : video_(path, rate_hz, slack_events_only) {}
  void OnVideoTick(sim::World& world, const LogRow& now, const cv::Mat& onboard) override {
    (void)onboard;
    world.RenderPayloadCamera(&onboard_, cv::Rect());
    VideoRecorder::Hud hud{now.time_s, now.truth.mode, now.estimate.mode, now.command.thrust_N,
                           now.cable_tension_N};
    video_.AddFrame(world.RenderChaseCamera(VideoRecorder::kWidthPx, VideoRecorder::kHeightPx),
                    onboard_, hud);
  }
  void Finish() { video_.Finish(); }

 private:
  VideoRecorder video_;
  cv::Mat onboard_;  // the whole onboard frame of the latest video tick
};

// The PX4 rate loop's parameters from the world profile's rate_loop section.
Px4RateParams Px4ParamsOf(const sim::RateLoopProfile& r) {
  const auto v = [](const std::array<double, 3>& a) { return Eigen::Vector3d(a[0], a[1], a[2]); };
  Px4RateParams p;
  p.rate_hz = r.rate_hz;
  p.p = v(r.p);
  p.i = v(r.i);
  p.d = v(r.d);
  p.k = v(r.k);
  p.integrator_limit = v(r.integrator_limit);
  p.gyro_cutoff_hz = r.gyro_cutoff_hz;
  p.dgyro_cutoff_hz = r.dgyro_cutoff_hz;
  p.yaw_torque_cutoff_hz = r.yaw_torque_cutoff_hz;
  return p;
}

}  // namespace

namespace {
volatile std::sig_atomic_t g_stop_signal = 0;  // set from a signal handler
}  // namespace

void RequestStop(int signal_number) { g_stop_signal = signal_number; }

int StopRequested() { return g_stop_signal; }

RateTable ScenarioRates(const Scenario& scenario) {
  RateTable rates;
  rates.camera.latency_s = scenario.estimation.camera_latency_s;
  return rates;
}

std::vector<RateRow> ScenarioRateTable(const Scenario& scenario, const Params& params) {
  const RateTable rates = ScenarioRates(scenario);
  const sim::LatencyProfile& latency = scenario.world.latency;
  const std::unique_ptr<Controller> controller =
      MakeController(scenario.controller, params, MakeReference(scenario, params));
  std::vector<RateRow> rows = {
      {"physics", 1.0 / sim::World::kPhysicsDt_s, 0.0, "MuJoCo timestep (sim::World)"},
      {"imu", rates.imu.rate_hz, rates.imu.latency_s, "RateTable::imu"},
  };
  if (scenario.world.rate_loop.px4) {
    rows.push_back({"rate loop (PX4) and its gyro", scenario.world.rate_loop.rate_hz, 0.0,
                    "world profile rate_loop.rate_hz"});
  } else {
    rows.push_back({"rate loop (body-rate P)", rates.imu.rate_hz, 0.0, "RateTable::imu"});
  }
  rows.push_back({"vio", rates.vio.rate_hz, rates.vio.latency_s, "RateTable::vio"});
  if (!scenario.estimation.ground_truth) {
    rows.push_back({"camera (" + scenario.estimation.camera + ")", rates.camera.rate_hz,
                    rates.camera.latency_s, "RateTable::camera, estimation.camera_latency"});
  }
  rows.push_back({"control (" + scenario.controller.type + ")", controller->RateHz(),
                  latency.compute_s + latency.transport_s,
                  "the controller's RateHz(); world profile latency.compute_s + transport_s"});
  rows.push_back(
      {"estimate to controller", 0.0, latency.estimate_s, "world profile latency.estimate_s"});
  rows.push_back({"video (--video)", rates.video.rate_hz, 0.0, "RateTable::video"});
  return rows;
}

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
  world_config.rates = ScenarioRates(scenario);
  world_config.profile = scenario.world;
  world_config.gl_backend = options.gl_backend;
  world_config.randomize_appearance = scenario.estimation.camera_randomize;
  const RateTable& rates = world_config.rates;
  sim::World world(world_config);
  metrics.world_profile = scenario.world.name;
  if (scenario.reference.type == "lissajous") {
    metrics.payload_rmse_from_s = scenario.reference.lissajous.ramp_s;
  }

  // flight code: reference, controller, rate loop, estimator (flight params only); the world
  // starts from its own parameters (mismatch draw and overrides)
  const std::shared_ptr<const Reference> reference = MakeReference(scenario, params);
  CheckReferenceAboveGround(*reference, scenario.duration_s, params);
  world.Reset(InitialState(*reference, world.world_params()));
  std::unique_ptr<Controller> controller = MakeController(scenario.controller, params, reference);
  BodyRateController rate_controller(params);
  // the profile may fly PX4's rate loop instead, on the world's rate gyro
  std::unique_ptr<Px4RateController> px4_rate;
  if (scenario.world.rate_loop.px4) {
    px4_rate = std::make_unique<Px4RateController>(params, Px4ParamsOf(scenario.world.rate_loop));
  }
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
  sim::AnalyticCamera analytic_camera(params, camera_noise);
  std::mt19937_64 camera_rng(scenario.seed * 0x9E3779B97F4A7C15ULL + 17);

  // recorders: the log and metrics inputs, the video, the caller's
  MetricsInputs inputs;
  LogRecorder log_recorder(&inputs);
  std::vector<RunRecorder*> recorders{&log_recorder};
  std::unique_ptr<VideoTickRecorder> video;
  if (!options.video_path.empty()) {
    video = std::make_unique<VideoTickRecorder>(options.video_path, rates.video.rate_hz,
                                                options.video_slack_events_only);
    recorders.push_back(video.get());
  }
  recorders.insert(recorders.end(), options.recorders.begin(), options.recorders.end());

  // lockstep schedule on the physics clock
  const double end_s = std::min(scenario.duration_s, options.stop_at_s.value_or(1e300));
  const long end_tick = static_cast<long>(std::llround(end_s / sim::World::kPhysicsDt_s));
  LockstepClock clock(rates.physics_hz);
  const int camera_loop = clock.AddLoop("camera", rates.camera.rate_hz);
  const int control_loop = clock.AddLoop("control", controller->RateHz());
  const int rate_loop = px4_rate ? -1 : clock.AddLoop("rate", rates.imu.rate_hz);
  const int video_loop = video ? clock.AddLoop("video", rates.video.rate_hz) : -1;
  const double rate_loop_dt_s = 1.0 / rates.imu.rate_hz;
  size_t next_event = 0;
  std::vector<EventSpec> events = scenario.events;
  std::stable_sort(events.begin(), events.end(),
                   [](const EventSpec& a, const EventSpec& b) { return a.at_s < b.at_s; });
  DelayLine<PayloadDetection> in_flight(rates.camera.latency_s);  // camera to estimator
  ControlOutput control;  // the command the rate loop tracks
  control.command.thrust_N = params.HoverThrustN();
  // latencies of the flight code (world profile): a command reaches the rate loop compute +
  // transport after the state it was computed from; the controller reads an estimate that is
  // estimate_s old
  const sim::LatencyProfile& latency = scenario.world.latency;
  DelayLine<ControlOutput> commands_in_flight(latency.compute_s + latency.transport_s);
  const bool delayed_estimate = latency.estimate_s > 0.0;
  DelayLine<SystemState> estimates_in_flight(latency.estimate_s);
  SystemState delayed_state;  // latest estimate old enough to have reached the controller
  bool have_delayed_state = false;
  const bool show_progress = options.progress && isatty(STDERR_FILENO);
  int last_progress_pct = -1;

  long tick = 0;
  cv::Mat rendered;                 // the payload camera's frame buffer, reused frame to frame
  PayloadDetection last_detection;  // the region of the next frame is around it
  bool mixer_saturated = false;     // the rate loop's last allocation fell short
  try {
    for (; tick <= end_tick; ++tick, clock.Advance()) {
      const double t = tick * sim::World::kPhysicsDt_s;
      if (g_stop_signal != 0) {
        throw std::runtime_error("stopped by signal " + std::to_string(g_stop_signal));
      }

      // scripted disturbances
      while (next_event < events.size() && events[next_event].at_s <= t + 1e-9) {
        ApplyEvent(events[next_event++], &world);
      }

      // which loops run at this tick; truth and the flight state only when one needs them
      clock.BeginTick();
      const bool camera_due = clock.Fires(camera_loop);
      const bool control_due = clock.Fires(control_loop);
      const bool rate_due = rate_loop >= 0 && clock.Fires(rate_loop);
      const bool video_due = video_loop >= 0 && clock.Fires(video_loop);
      const bool need_state = control_due || rate_due || video_due || delayed_estimate;
      sim::Truth truth;
      if (camera_due || control_due || video_due || (ground_truth && need_state)) {
        truth = world.GetTruth();
      }

      // payload camera: capture now, deliver after the latency
      if (camera_due) {
        const Eigen::Vector3d p_CL_C = PayloadInCamera_C(params, truth.state);
        CameraFrameRecord frame;
        frame.time_s = t;
        frame.payload_in_image = InsideImage(params, p_CL_C);
        if (!ground_truth) {
          PayloadDetection detection;
          if (render_camera) {
            // the region around the last detection first; the whole frame when the region
            // cannot decide (DetectInRegion's result equals the whole frame's when it gives one).
            // Recorders never change this path: a video renders frames of its own.
            const cv::Rect region = detector.RegionAround(last_detection, kRegionMarginPx);
            // renders `area` (empty: the whole frame) and detects in it; times add up
            const auto render_and_detect = [&](const cv::Rect& area) {
              world.RenderPayloadCamera(&rendered, area);
              frame.render_ms += world.last_camera_timing().render_ms;
              frame.image_model_ms += world.last_camera_timing().image_model_ms;
              const auto r1 = Clock::now();
              const std::optional<PayloadDetection> d =
                  area.area() > 0 ? detector.DetectInRegion(rendered, area, t)
                                  : std::optional<PayloadDetection>(detector.Detect(rendered, t));
              frame.detector_ms += Ms(r1, Clock::now());
              return d;
            };
            std::optional<PayloadDetection> in_region;
            if (region.area() > 0) in_region = render_and_detect(region);
            frame.region_only = in_region.has_value();
            detection = in_region ? *in_region : *render_and_detect(cv::Rect());
            last_detection = detection;
            frame.frame = &rendered;
          } else {
            detection = analytic_camera.Measure(p_CL_C, t, camera_rng);
          }
          frame.detected = detection.found;
          in_flight.Push(detection.time_s, detection);
        }
        for (RunRecorder* r : recorders) r->OnCameraFrame(frame);
      }
      while (auto detection = in_flight.PopReady(t)) estimator->OnPayloadDetection(*detection);

      // what flight code sees
      SystemState state;
      if (need_state) state = ground_truth ? truth.state : estimator->Estimate(t);
      state.time_s = t;

      // the estimate the controller may read: now, or estimate_s ago (labelled with the time it
      // is read: the controller does not know its age)
      SystemState controller_state = state;
      if (delayed_estimate) {
        estimates_in_flight.Push(t, state);
        while (auto old = estimates_in_flight.PopReady(t)) {
          delayed_state = *old;
          have_delayed_state = true;
        }
        if (have_delayed_state) controller_state = delayed_state;
        controller_state.time_s = t;
      }

      // high-level controller; its command reaches the rate loop after compute + transport
      if (control_due) {
        const ControlOutput computed = controller->Update(controller_state);
        commands_in_flight.Push(t, computed);
        LogRow row;
        row.time_s = t;
        row.truth = truth.state;
        row.estimate = state;
        row.reference = reference->At(t);
        row.command = computed.command;
        row.status = computed.status;
        row.solve_time_ms = computed.solve_time_ms;
        row.cost = computed.cost;
        row.cable_tension_N = truth.cable_tension_N;
        row.gripper_active = world.gripper_active();
        row.mixer_saturated = mixer_saturated;
        if (!ground_truth) {
          const EstimatorHealth health = estimator->Health();
          row.estimator_rejected_updates = health.RejectedUpdates();
          row.estimator_resets = health.ForcedAccepts();
        }
        for (RunRecorder* r : recorders) r->OnControlStep(row);
      }

      while (auto arrived = commands_in_flight.PopReady(t)) control = *arrived;

      // body-rate loop: PX4's runs on each new sample of its gyro (none yet at the first tick:
      // the motors keep the world's initial hover command)
      // the estimator is told the thrust the allocation made (a saturated mixer lowers it)
      if (px4_rate) {
        if (const std::optional<GyroSample> gyro = world.TakeRateGyro()) {
          world.SetMotorSpeedCommand(px4_rate->Update(control.command, gyro->gyro_B_radps));
          const Px4RateStatus& mixer = px4_rate->status();
          if (!ground_truth) estimator->OnAllocatedThrust(mixer.thrust_allocated_N);
          ++inputs.rate_loop_steps;
          inputs.mixer_saturated_steps += mixer.saturated ? 1 : 0;
          mixer_saturated = mixer.saturated;
        }
      } else if (rate_due) {
        const InputVector w_cmd =
            rate_controller.Update(control.command, state.w_B, rate_loop_dt_s);
        world.SetMotorSpeedCommand(w_cmd);
        const double allocated_N = params.k_f_N_per_radps2 * w_cmd.squaredNorm();
        if (!ground_truth) estimator->OnAllocatedThrust(allocated_N);
        ++inputs.rate_loop_steps;
        mixer_saturated = allocated_N < control.command.thrust_N - 1e-6;
        inputs.mixer_saturated_steps += mixer_saturated ? 1 : 0;
      }

      // video frame
      if (video_due) {
        LogRow now;
        now.time_s = t;
        now.truth = truth.state;
        now.estimate = state;
        now.command = control.command;
        now.cable_tension_N = truth.cable_tension_N;
        for (RunRecorder* r : recorders) r->OnVideoTick(world, now, cv::Mat());
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
  metrics.payload_quad_min_distance_m = world.payload_quad_min_distance_m();
  const sim::ContactCounts& contacts = world.contact_counts();
  metrics.contacts_payload_body = contacts.payload_body;
  metrics.contacts_payload_rotor = contacts.payload_rotor;
  metrics.contacts_payload_ground = contacts.payload_ground;
  metrics.contacts_quad_ground = contacts.quad_ground;
  metrics.contacts_payload_gripper = contacts.payload_gripper;
  ComputeMetrics(inputs, &metrics);
  result.rows = std::move(inputs.rows);
  CheckExpectations(scenario.expect, &metrics);
  metrics.wall_time_s = Ms(wall_start, Clock::now()) / 1000.0;
  return result;
}

}  // namespace hpa
