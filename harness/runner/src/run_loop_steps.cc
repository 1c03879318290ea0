// RunLoop's per-tick steps (Tick calls them in this order): the payload camera and its read-out
// by the flight stack, the control step and the commands in flight, the body-rate loop, the
// video tick and the physics step with the routing of the world's sensor messages.
#include <chrono>
#include <optional>
#include <utility>

#include "harness/runner/src/run_loop.h"

namespace hpa::runner {
namespace {

double Ms(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// An attitude as the (w, x, y, z) vector TiltDeg reads.
Eigen::Vector4d Wxyz(const Eigen::Quaterniond& q) { return {q.w(), q.x(), q.y(), q.z()}; }

}  // namespace

// The payload camera: the world captures it if due (its message delivered after its latency),
// a rendered frame read out by the flight stack in the region it asked for; then the camera's
// messages delivered by now join this tick's inputs. A camera not flown (a stack that uses no
// pixels) reads nothing out and records no frame: the capture only keeps the world's clocks and
// the gripper's switch.
void RunLoop::CameraStep() {
  cv::Rect region;
  if (render_camera_ && world_->CameraFrameDue()) {
    region = flight_->detects_at_capture() ? flight_->CaptureRegion() : stack_roi_;
  }
  std::optional<sim::CameraCapture> capture = world_->CaptureTickStart(region);
  if (capture && metrics_->camera_flown) {
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
    UpdateVehicleExtremes(Wxyz(truth.state.q_WB), truth.cable_tension_N, &inputs_.extremes);
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
    UpdateVehicleExtremes(Wxyz(truth.state.q_WB), truth.cable_tension_N, &inputs_.extremes);
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

}  // namespace hpa::runner
