#include "hpa/flight/flight_stack.h"

#include "hpa/estimator/estimator.h"
#include "hpa/estimator/estimator_registry.h"
#include "hpa/estimator/payload_detector.h"

namespace hpa::flight {

PayloadDetection DetectFrame(const PayloadDetector& detector, const CameraFrame& frame) {
  if (frame.region.area() > 0 && !frame.region_bgr.empty()) {
    if (std::optional<PayloadDetection> d =
            detector.DetectInRegion(frame.region_bgr, frame.region, frame.capture_time_s)) {
      return *d;
    }
  }
  return detector.Detect(frame.whole_bgr, frame.capture_time_s);
}

FlightStack::FlightStack(const FlightConfig& config)
    : config_(config), clock_(config.tick_hz), estimates_in_flight_(config.estimate_latency_s) {
  controller_ = MakeController(config.controller, config.params,
                               MakeReference(config.reference, config.params));
  control_loop_ = clock_.AddLoop("control", controller_->RateHz());
  if (!config.ground_truth) {
    EstimatorConfig estimator_config;
    estimator_config.tension_cue.enabled = config.slack_tension_cue;
    estimator_ =
        MakeEstimator(config.estimator, estimator_config, config.params, config.initial_state);
    detector_ = std::make_unique<PayloadDetector>(config.params);
  }
}

FlightStack::~FlightStack() = default;

int FlightStack::Deliver(const FlightInputs& in) {
  if (!estimator_) return 0;  // ground truth: nothing reads the sensors
  if (in.allocation) estimator_->OnAllocatedThrust(in.allocation->thrust_allocated_N);
  for (const ImuSample& imu : in.imu) estimator_->OnImu(imu);
  for (const VioSample& vio : in.vio) estimator_->OnVio(vio);
  for (const PayloadDetection& d : in.detections) estimator_->OnPayloadDetection(d);
  int found = 0;
  for (const CameraFrame& frame : in.frames) {
    last_detection_ = DetectFrame(*detector_, frame);
    found += last_detection_.found ? 1 : 0;
    estimator_->OnPayloadDetection(last_detection_);
  }
  return found;
}

int FlightStack::Finish(const FlightInputs& in) {
  FlightInputs sensors = in;
  sensors.frames.clear();
  Deliver(sensors);
  int found = 0;
  for (const CameraFrame& frame : in.frames) {
    if (!detector_) break;
    last_detection_ = DetectFrame(*detector_, frame);
    found += last_detection_.found ? 1 : 0;
  }
  return found;
}

FlightOutputs FlightStack::Step(const FlightInputs& in) {
  FlightOutputs out;
  out.frames_detected = Deliver(in);
  clock_.BeginTick();
  const bool control_due = clock_.Fires(control_loop_);
  const bool delayed = config_.estimate_latency_s > 0.0;
  if (control_due || in.need_estimate || delayed) {
    if (config_.ground_truth && !in.truth) {
      throw std::invalid_argument("the ground-truth switch is on but no truth came at t = " +
                                  std::to_string(in.time_s) + " s");
    }
    SystemState state = config_.ground_truth ? *in.truth : estimator_->Estimate(in.time_s);
    state.time_s = in.time_s;
    out.has_estimate = true;
    out.estimate = state;
    // the estimate the controller may read: now, or estimate_latency_s ago (labelled with the
    // time it is read: the controller does not know its age)
    SystemState controller_state = state;
    if (delayed) {
      estimates_in_flight_.Push(in.time_s, state);
      while (std::optional<SystemState> old = estimates_in_flight_.PopReady(in.time_s)) {
        delayed_state_ = *old;
        have_delayed_state_ = true;
      }
      if (have_delayed_state_) controller_state = delayed_state_;
      controller_state.time_s = in.time_s;
    }
    if (control_due) {
      out.has_command = true;
      out.command = controller_->Update(controller_state);
    }
  }
  if (detector_) out.camera_roi = detector_->RegionAround(last_detection_, kRegionMarginPx);
  if (estimator_) {
    const hpa::EstimatorHealth health = estimator_->Health();
    out.estimator_rejected_updates = health.RejectedUpdates();
    out.estimator_resets = health.ForcedAccepts();
  }
  clock_.Advance();
  return out;
}

HealthFields FlightStack::EstimatorHealth() const {
  return estimator_ ? estimator_->Health().Fields() : HealthFields{};
}

double FlightStack::control_rate_hz() const { return controller_->RateHz(); }

}  // namespace hpa::flight
