#include "hpa/flight/flight_stack.h"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "hpa/estimator/estimator.h"
#include "hpa/estimator/estimator_registry.h"
#include "hpa/estimator/payload_detector.h"

namespace hpa::flight {

// The controller's updates on a thread of their own, in the order they were submitted; their
// results taken in the same order. The controller is touched by this thread only while it runs.
class ControlThread {
 public:
  explicit ControlThread(Controller* controller)
      : controller_(controller), slots_(kInitialSlots), thread_([this] { Loop(); }) {}

  // Finishes the updates already submitted (their results are dropped), then joins.
  ~ControlThread() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    work_cv_.notify_one();
    thread_.join();
  }

  ControlThread(const ControlThread&) = delete;
  ControlThread& operator=(const ControlThread&) = delete;

  // Queues Update(state).
  void Submit(const SystemState& state) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      if (submitted_ - awaited_ == slots_.size()) {
        // every slot holds a result not yet taken: once the thread is idle, twice the slots,
        // each pending one at its place in the larger ring
        done_cv_.wait(lock, [&] { return computed_.load() == submitted_; });
        std::vector<Slot> larger(2 * slots_.size());
        for (uint64_t n = awaited_; n < submitted_; ++n) {
          larger[n % larger.size()] = std::move(slots_[n % slots_.size()]);
        }
        slots_ = std::move(larger);
      }
      slots_[submitted_ % slots_.size()].state = state;
      ++submitted_;
    }
    work_cv_.notify_one();
  }

  // The oldest result not yet taken (waits for it); rethrows the controller's exception.
  ControlOutput Await() {
    if (awaited_ == submitted_) {
      throw std::logic_error("FlightStack::AwaitCommand: no control step is pending");
    }
    // the result is usually near: a short spin before sleeping on the condition variable
    const auto spin_until = std::chrono::steady_clock::now() + std::chrono::microseconds(100);
    for (int i = 0; computed_.load(std::memory_order_acquire) <= awaited_; ++i) {
#if defined(__x86_64__)
      __builtin_ia32_pause();  // a spin-wait hint: the other hardware thread runs meanwhile
#endif
      if ((i & 63) == 63 && std::chrono::steady_clock::now() > spin_until) break;
    }
    Slot taken;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      done_cv_.wait(lock, [&] { return computed_.load() > awaited_; });
      taken = std::move(slots_[awaited_ % slots_.size()]);
      ++awaited_;
    }
    if (taken.error) std::rethrow_exception(taken.error);
    return taken.output;
  }

 private:
  // One submitted update: its input, then its output or what it threw.
  struct Slot {
    SystemState state;
    ControlOutput output;
    std::exception_ptr error;
  };
  static constexpr size_t kInitialSlots = 4;

  void Loop() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      work_cv_.wait(lock, [&] { return stop_ || computed_.load() < submitted_; });
      if (computed_.load() == submitted_) return;  // stopped with nothing left
      const uint64_t n = computed_.load();
      const SystemState state = slots_[n % slots_.size()].state;
      lock.unlock();
      ControlOutput output;
      std::exception_ptr error;
      try {
        output = controller_->Update(state);
      } catch (...) {
        error = std::current_exception();
      }
      lock.lock();
      Slot& slot = slots_[n % slots_.size()];
      slot.output = std::move(output);
      slot.error = error;
      computed_.store(n + 1, std::memory_order_release);
      done_cv_.notify_one();
    }
  }

  Controller* controller_;
  std::mutex mutex_;
  std::condition_variable work_cv_;  // a new update or the stop
  std::condition_variable done_cv_;  // an update finished
  std::vector<Slot> slots_;          // ring: update n in slot n % size
  uint64_t submitted_ = 0;           // updates queued (written under mutex_)
  std::atomic<uint64_t> computed_{0};  // updates finished (written under mutex_)
  uint64_t awaited_ = 0;             // results taken (the submitting thread only)
  bool stop_ = false;
  std::thread thread_;  // last: starts once the members above exist
};

PayloadDetection DetectFrame(const PayloadDetector& detector, const CameraFrame& frame,
                             const WholeFrameReader& read_whole) {
  if (frame.region.area() > 0 && !frame.region_bgr.empty()) {
    if (std::optional<PayloadDetection> d =
            detector.DetectInRegion(frame.region_bgr, frame.region, frame.capture_time_s)) {
      return *d;
    }
  }
  // DetectInRegion's result equals the whole frame's when it gives one, so the whole frame is
  // read out only here
  const bool read = frame.whole_bgr.empty() && read_whole;
  return detector.Detect(read ? read_whole() : frame.whole_bgr, frame.capture_time_s);
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
  }
  // with ground truth too: the rendered camera's detections are recorded (no estimator reads
  // them, so the region stays the whole frame)
  detector_ = std::make_unique<PayloadDetector>(config.params);
  if (config.control_thread) control_thread_ = std::make_unique<ControlThread>(controller_.get());
}

FlightStack::~FlightStack() = default;

int FlightStack::Deliver(const FlightInputs& in) {
  if (!estimator_) return 0;  // ground truth: nothing reads the sensors
  if (in.allocation) estimator_->OnAllocatedThrust(in.allocation->thrust_allocated_N);
  for (const ImuSample& imu : in.imu) estimator_->OnImu(imu);
  for (const VioSample& vio : in.vio) estimator_->OnVio(vio);
  for (const PayloadDetection& d : in.detections) {
    recent_detections_.Push(d);
    estimator_->OnPayloadDetection(d);
  }
  int found = 0;
  for (const CameraFrame& frame : in.frames) {
    recent_detections_.Push(DetectFrame(*detector_, frame));
    found += recent_detections_.last.found ? 1 : 0;
    estimator_->OnPayloadDetection(recent_detections_.last);
  }
  return found;
}

int FlightStack::Finish(const FlightInputs& in) {
  FlightInputs sensors = in;
  sensors.frames.clear();
  Deliver(sensors);
  int found = 0;
  for (const CameraFrame& frame : in.frames) {
    if (!estimator_) break;  // ground truth: no flight code reads them
    recent_detections_.Push(DetectFrame(*detector_, frame));
    found += recent_detections_.last.found ? 1 : 0;
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
      if (control_thread_) {
        control_thread_->Submit(controller_state);
        out.command_pending = true;
      } else {
        out.command = controller_->Update(controller_state);
      }
    }
  }
  if (detector_) out.camera_roi = detector_->RegionAround(recent_detections_, kRegionMarginPx);
  if (estimator_) {
    const hpa::EstimatorHealth health = estimator_->Health();
    out.estimator_rejected_updates = health.RejectedUpdates();
    out.estimator_resets = health.ForcedAccepts();
    out.estimator_health_resets = health.health_resets;
  }
  clock_.Advance();
  return out;
}

ControlOutput FlightStack::AwaitCommand() {
  if (!control_thread_) {
    throw std::logic_error("FlightStack::AwaitCommand: the controller runs on the caller's thread");
  }
  return control_thread_->Await();
}

cv::Rect FlightStack::CameraRegion() const {
  return detector_ ? detector_->RegionAround(recent_detections_, kRegionMarginPx) : cv::Rect();
}

std::optional<PayloadDetection> FlightStack::DetectCaptured(const CameraFrame& frame) const {
  if (frame.whole_bgr.empty()) {
    if (frame.region.area() <= 0 || frame.region_bgr.empty()) return std::nullopt;
    return detector_->DetectInRegion(frame.region_bgr, frame.region, frame.capture_time_s);
  }
  return DetectFrame(*detector_, frame);
}

PayloadDetection FlightStack::DetectCaptured(const CameraFrame& frame,
                                             const WholeFrameReader& read_whole) const {
  return DetectFrame(*detector_, frame, read_whole);
}

HealthFields FlightStack::EstimatorHealth() const {
  return estimator_ ? estimator_->Health().Fields() : HealthFields{};
}

double FlightStack::control_rate_hz() const { return controller_->RateHz(); }

}  // namespace hpa::flight
