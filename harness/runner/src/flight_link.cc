#include "harness/runner/src/flight_link.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <deque>

#include "hpa/scenarios/runner.h"
#include "harness/runner/src/flight_process.h"
#include "harness/runner/src/frame_ring.h"
#include "harness/runner/src/reply_order.h"
#include "harness/runner/src/stack_process.h"

namespace hpa::runner {
namespace {

using flight::Channel;
using flight::MessageType;
using flight::ProtocolError;

class InProcessFlight final : public FlightLink {
 public:
  explicit InProcessFlight(const flight::FlightConfig& config) : stack_(config) {}
  flight::FlightOutputs Step(const flight::FlightInputs& in) override { return stack_.Step(in); }
  // the stack's detector at capture, in the region around its last detections (with ground
  // truth the flight code reads no frame: the detections are only recorded, whole frames)
  bool detects_at_capture() const override { return true; }
  cv::Rect CaptureRegion() override { return stack_.CameraRegion(); }
  PayloadDetection DetectCaptured(const CameraFrame& frame,
                                  const WholeFrameReader& read_whole) override {
    return stack_.DetectCaptured(frame, read_whole);
  }
  ControlOutput AwaitCommand() override { return stack_.AwaitCommand(); }
  FlightFinish Finish(const flight::FlightInputs& pending) override {
    FlightFinish f;
    f.frames_detected = stack_.Finish(pending);
    f.estimator = stack_.config().ground_truth ? "" : stack_.config().estimator;
    f.estimator_health = stack_.EstimatorHealth();
    return f;
  }
  std::string name() const override { return "in_process"; }
  std::string controller() const override { return stack_.config().controller.type; }
  double control_rate_hz() const override { return stack_.control_rate_hz(); }

 private:
  flight::FlightStack stack_;
};

// A separate flight stack: its process, the socket it connected to and the frame ring.
class ExternalFlight final : public FlightLink {
 public:
  ExternalFlight(const flight::FlightConfig& config, const ExternalFlightOptions& options)
      : options_(options),
        process_("flight stack '" + options.command + "'", options.step_timeout_s),
        params_(config.params),
        tick_hz_(config.tick_hz),
        control_clock_(config.tick_hz) {
    try {
      Start(config);
    } catch (...) {
      Cleanup();
      throw;
    }
  }

  ~ExternalFlight() override { Cleanup(); }

  void Start(const flight::FlightConfig& config) {
    const ExternalFlightOptions& options = options_;
    // what earlier runs of killed hpa processes left behind, before this run adds its own
    RemoveStaleFlightRuns();
    static std::atomic<int> counter{0};
    const int n = counter++;
    if (options.frames.slots > 0) {
      ring_ = std::make_unique<FrameRing>(
          "/hpa-flight-" + FlightOwnerTag() + "-" + std::to_string(n), options.frames.slots,
          options.frames.width_px, options.frames.height_px);
    }
    process_.Start(options.command);
    process_.Accept(StackProcess::After(options.connect_timeout_s), options.connect_timeout_s);
    nlohmann::json hello = {{"protocol_version", flight::kProtocolVersion},
                            {"scenario", options.scenario},
                            {"seed", options.seed},
                            {"rates", options.rates},
                            {"config", flight::ConfigToJson(config)},
                            {"rate_loop", flight::RateLoopToJson(options.rate_loop)}};
    if (ring_) {
      hello["camera"] = {{"ring", ring_->name()},
                         {"slots", options.frames.slots},
                         {"width_px", options.frames.width_px},
                         {"height_px", options.frames.height_px},
                         {"slot_bytes", ring_->slot_bytes()}};
    }
    process_.Guard(
        [&] {
          channel().SendJson(MessageType::kHello, hello, Limit());
          const flight::HelloAck ack = flight::ParseHelloAck(
              channel().Expect(MessageType::kHelloAck, Limit()), config.tick_hz);
          name_ = ack.name;
          // a stack that names no controller flies its own: its name labels the run
          controller_ = !ack.controller.empty() ? ack.controller
                        : !ack.name.empty()     ? ack.name
                                                : "external";
          control_rate_hz_ = ack.control_rate_hz;
          // the rendered frames: none for a stack that uses no pixels (the ring the hello named
          // goes), read at capture by a stack that says it can, else all sent
          uses_pixels_ = ack.uses_pixels;
          if (!uses_pixels_) ring_.reset();
          detects_at_capture_ = ring_ && ack.detects_at_capture;
          // batched ticks: the replies the simulator needs follow the stack's control loop and
          // the ticks that read the estimate; the region a rendered frame reads follows the
          // camera's captures, so a stack that receives every frame is asked every tick
          batched_ = ack.batched_ticks && (!ring_ || detects_at_capture_);
          if (batched_) control_loop_ = control_clock_.AddLoop("control", ack.control_rate_hz);
          owns_rate_loop_ = ack.owns_rate_loop;
        },
        "hello");
  }

  // Stops the process and removes its socket (StackProcess::Cleanup), then frees the ring.
  void Cleanup() {
    process_.Cleanup();
    ring_.reset();
  }

  flight::FlightOutputs Step(const flight::FlightInputs& in) override {
    flight::FlightOutputs out;
    messages_so_far_ += in.imu.size() + in.vio.size() + in.detections.size() + in.frames.size();
    frames_unanswered_ += in.frames.size();
    next_tick_s_ = in.time_s + 1.0 / tick_hz_;
    if (!batched_) {
      process_.Guard(
          [&] {
            if (ring_) ring_->Check();  // frames rendered into a ring cut short are never sent
            CheckNothingUnasked();
            channel().Send(MessageType::kTick, flight::EncodeTick(in), Limit());
            out = flight::DecodeReply(channel().Expect(MessageType::kTickReply, Limit()));
            flight::CheckReply(out, Bounds(in));
            replies_.TickAnswered(out, in.time_s);
          },
          "tick at t = " + std::to_string(in.time_s) + " s");
      frames_unanswered_ = 0;
      return out;
    }
    // batched: this tick waits in the queue unless its reply is needed (the estimate now, a
    // command later); its reply is read when it is needed
    control_clock_.BeginTick();
    const bool control = control_clock_.Fires(control_loop_);
    control_clock_.Advance();
    const bool wanted = control || in.need_estimate;
    process_.Guard(
        [&] {
          if (ring_) ring_->Check();
          CheckNothingUnasked();
          tick_ = in;  // the tick as sent: no_reply when no reply to it is read
          tick_.no_reply = !wanted;
          channel().Queue(MessageType::kTick, flight::EncodeTick(tick_));
          if (!wanted) return;
          awaited_.push_back({in.time_s, Bounds(in), control});
          frames_unanswered_ = 0;
          channel().Flush(Limit());
          if (in.need_estimate) {
            while (!awaited_.empty()) out = ReadReply();
          }
        },
        "tick at t = " + std::to_string(in.time_s) + " s");
    if (!in.need_estimate) {
      // its command (if its control loop fired) is taken later, with its estimate and health
      out = flight::FlightOutputs();
      out.has_command = control;
      out.camera_roi = last_roi_;
    }
    // every command is taken when it is due, as the in-process control thread's are (the log
    // rows keep the order of the control steps)
    out.command_pending = out.has_command;
    out.frames_detected = std::exchange(frames_found_, 0);
    return out;
  }

  flight::FlightOutputs AwaitReply() override {
    flight::FlightOutputs out;
    process_.Guard(
        [&] {
          while (commands_.empty()) {
            if (awaited_.empty()) throw std::logic_error("no control step awaits its command");
            ReadReply();
          }
          out = std::move(commands_.front());
          commands_.pop_front();
        },
        "the command of the control step at t = " + std::to_string(PendingCommandTime()) + " s");
    return out;
  }
  ControlOutput AwaitCommand() override { return AwaitReply().command; }

  bool detects_at_capture() const override { return detects_at_capture_; }
  bool uses_pixels() const override { return uses_pixels_; }

  cv::Rect CaptureRegion() override {
    flight::DetectReply reply;
    CameraFrame frame;
    frame.capture_time_s = next_tick_s_;
    process_.Guard(
        [&] {
          reply = Detect(frame);
          if (reply.has_detection) {
            throw ProtocolError("detect_reply refused: a detection before any pixels");
          }
        },
        "detect at t = " + std::to_string(next_tick_s_) + " s");
    capture_region_ = reply.region_wanted ? reply.camera_roi : cv::Rect();
    return capture_region_;
  }

  PayloadDetection DetectCaptured(const CameraFrame& captured,
                                  const WholeFrameReader& read_whole) override {
    PayloadDetection detection;
    const std::string step = "detect at t = " + std::to_string(captured.capture_time_s) + " s";
    CameraFrame frame;
    frame.capture_time_s = captured.capture_time_s;
    flight::DetectReply reply;
    reply.whole_wanted = true;
    // the region the stack asked for, into the ring's first slot
    if (captured.region.area() > 0 && !captured.region_bgr.empty()) {
      process_.Guard(
          [&] {
            ring_->Check();
            cv::Mat* slot = ring_->Slot(0);
            const cv::Rect& roi = captured.region;
            if (captured.region_bgr.size() == slot->size()) {
              captured.region_bgr(roi).copyTo((*slot)(roi));
            } else {
              captured.region_bgr.copyTo((*slot)(roi));
            }
            frame.region = roi;
            frame.region_slot = 0;
            reply = Detect(frame);
            if (reply.region_wanted) throw ProtocolError("detect_reply refused: a second region");
          },
          step);
    }
    if (reply.has_detection) return reply.detection;
    // the whole frame, into the second slot
    const cv::Mat& whole = read_whole();
    process_.Guard(
        [&] {
          ring_->Check();
          whole.copyTo(*ring_->Slot(1));
          frame.whole_slot = 1;
          reply = Detect(frame);
          if (!reply.has_detection) {
            throw ProtocolError("detect_reply refused: no detection in the whole frame");
          }
        },
        step);
    return reply.detection;
  }

  bool owns_rate_loop() const override { return owns_rate_loop_; }

  // Sends the rate_tick after the ticks queued before it and reads its rate_reply (the replies
  // of the ticks before it first).
  AutopilotOutput RateLoop(const flight::RateTick& tick) override {
    AutopilotOutput out;
    process_.Guard(
        [&] {
          CheckNothingUnasked();
          channel().Queue(MessageType::kRateTick, flight::EncodeRateTick(tick));
          channel().Flush(Limit());
          std::vector<uint8_t> body;
          while (true) {
            const MessageType type = channel().Receive(&body, Limit());
            if (type == MessageType::kRateReply) break;
            if (type != MessageType::kTickReply || awaited_.empty()) {
              throw ProtocolError("expected a rate_reply message, got " +
                                  flight::MessageTypeName(type));
            }
            ReadReplyBody(body);
          }
          out = flight::DecodeRateReply(body);
          flight::CheckRateReply(out, params_);
          replies_.Answered("rate_tick at t = " + std::to_string(tick.time_s) + " s");
        },
        "rate loop at t = " + std::to_string(tick.time_s) + " s");
    return out;
  }

  FlightFinish Finish(const flight::FlightInputs& pending) override {
    FlightFinish f;
    // a stack that failed (or a wait a stop ended) is not asked again: the run error says why;
    // after a stop, only within its grace
    if (!process_.Finishable()) return f;
    const flight::WaitLimit limit = Limit();
    process_.Guard(
        [&] {
          if (ring_) ring_->Check();
          // the replies still on their way come first
          channel().Flush(limit);
          while (!awaited_.empty()) ReadReply();
          CheckNothingUnasked();
          channel().Send(MessageType::kFinish, flight::EncodeTick(pending), limit);
          // frames of ticks no reply answered are counted in the finish's
          const flight::FinishReply reply =
              flight::ParseFinishReply(channel().Expect(MessageType::kFinishReply, limit),
                                       pending.frames.size() + frames_unanswered_);
          f.estimator = reply.estimator;
          f.frames_detected = reply.frames_detected + std::exchange(frames_found_, 0);
          f.estimator_health = reply.estimator_health;
        },
        "finish");
    return f;
  }

  cv::Mat* NextFrameSlot(int* slot) override {
    if (!ring_) return nullptr;
    process_.Guard([&] { ring_->Check(); }, "frame ring");
    *slot = next_slot_;
    next_slot_ = (next_slot_ + 1) % options_.frames.slots;
    return ring_->Slot(*slot);
  }
  bool wants_reference() const override { return true; }
  std::string name() const override { return name_; }
  std::string controller() const override { return controller_; }
  double control_rate_hz() const override { return control_rate_hz_; }

 private:
  // A tick whose reply is read when it is needed.
  struct Awaited {
    double time_s;              // the tick's time
    flight::ReplyBounds bounds;  // what its reply is checked against
    bool control;               // its control loop fired: the reply carries a command, taken
                                // when it is due (AwaitReply)
  };

  // What a reply to `in` is checked against (the frames of the ticks it also answers).
  flight::ReplyBounds Bounds(const flight::FlightInputs& in) const {
    flight::ReplyBounds bounds;
    bounds.frames = frames_unanswered_;
    bounds.estimate_needed = in.need_estimate;
    bounds.messages_so_far = messages_so_far_;
    if (ring_) {
      bounds.image_width_px = options_.frames.width_px;
      bounds.image_height_px = options_.frames.height_px;
    }
    return bounds;
  }

  // The time of the oldest control step whose command is not taken yet (for messages).
  double PendingCommandTime() const {
    if (!commands_.empty()) return commands_.front().estimate.time_s;
    for (const Awaited& a : awaited_) {
      if (a.control) return a.time_s;
    }
    return next_tick_s_;
  }

  // Reads the reply of the oldest awaited tick and checks it against that tick; a command taken
  // later is kept for AwaitReply.
  flight::FlightOutputs ReadReply() {
    return ReadReplyBody(channel().Expect(MessageType::kTickReply, Limit()));
  }

  // The reply of the oldest awaited tick, from its body (as ReadReply).
  flight::FlightOutputs ReadReplyBody(const std::vector<uint8_t>& body) {
    const Awaited a = awaited_.front();
    awaited_.pop_front();
    const auto at = [&] {
      return " (the reply to the tick at t = " + std::to_string(a.time_s) + " s)";
    };
    flight::FlightOutputs out;
    try {
      out = flight::DecodeReply(body);
      flight::CheckReply(out, a.bounds);
      replies_.TickAnswered(out, a.time_s);
    } catch (const flight::WaitInterrupted&) {
      throw;
    } catch (const ProtocolError& e) {
      throw ProtocolError(e.what() + at());
    }
    if (out.has_command != a.control) {
      throw ProtocolError(std::string("tick_reply refused: ") +
                          (a.control ? "no command at a tick of its declared control rate"
                                     : "a command at a tick its declared control rate skips") +
                          at());
    }
    frames_found_ += out.frames_detected;
    last_roi_ = out.camera_roi;
    out.estimate.time_s = a.time_s;
    if (a.control) commands_.push_back(out);
    return out;
  }

  // Sends a detect (after the ticks queued before it) and reads its reply (the replies of the
  // ticks before it first).
  flight::DetectReply Detect(const CameraFrame& frame) {
    CheckNothingUnasked();
    channel().Queue(MessageType::kDetect, flight::EncodeDetect(frame));
    channel().Flush(Limit());
    std::vector<uint8_t> body;
    while (true) {
      const MessageType type = channel().Receive(&body, Limit());
      if (type == MessageType::kDetectReply) break;
      if (type != MessageType::kTickReply || awaited_.empty()) {
        throw ProtocolError("expected a detect_reply message, got " +
                            flight::MessageTypeName(type));
      }
      ReadReplyBody(body);
    }
    flight::DetectReply reply = flight::DecodeDetectReply(body);
    replies_.Answered("detect at t = " + std::to_string(frame.capture_time_s) + " s");
    const cv::Rect& roi = reply.camera_roi;
    if (reply.region_wanted &&
        (roi.width <= 0 || roi.height <= 0 || roi.x < 0 || roi.y < 0 ||
         roi.x > options_.frames.width_px - roi.width ||
         roi.y > options_.frames.height_px - roi.height)) {
      throw ProtocolError("detect_reply refused: camera_roi (" + std::to_string(roi.x) + ", " +
                          std::to_string(roi.y) + ", " + std::to_string(roi.width) + ", " +
                          std::to_string(roi.height) + ") empty or outside the " +
                          std::to_string(options_.frames.width_px) + " x " +
                          std::to_string(options_.frames.height_px) + " image");
    }
    return reply;
  }

  // Refuses a message the stack sent unasked: bytes waiting while no reply is awaited.
  void CheckNothingUnasked() {
    if (awaited_.empty()) replies_.CheckNothingUnasked(channel(), Limit());
  }

  // The connection to the stack, and one message's wait on it.
  Channel& channel() { return process_.channel(); }
  flight::WaitLimit Limit() { return process_.Limit(); }

  ExternalFlightOptions options_;
  StackProcess process_;  // its process and socket
  Params params_;  // the flight params (the motors' range a rate_reply is checked against)
  std::string name_ = "external", controller_ = "external";
  double control_rate_hz_ = 0.0;     // from the hello_ack (0: not stated)
  std::unique_ptr<FrameRing> ring_;  // the rendered frames, when they cross
  int next_slot_ = 0;
  uint64_t messages_so_far_ = 0;  // sensor messages sent (the estimator counters' bound)
  double tick_hz_;                // the lockstep clock's rate
  double next_tick_s_ = 0.0;      // time of the tick after the last one stepped
  bool detects_at_capture_ = false;  // the stack reads each rendered frame at its capture
  bool uses_pixels_ = true;          // the stack reads rendered frames (its hello_ack)
  bool batched_ = false;             // the stack declared batched_ticks (see Start)
  bool owns_rate_loop_ = false;      // the stack declared owns_rate_loop: it runs the rate loop
  LockstepClock control_clock_;      // the stack's control loop as it declared it (batched)
  int control_loop_ = -1;
  flight::FlightInputs tick_;               // the tick being sent (its storage reused)
  std::deque<Awaited> awaited_;             // ticks sent whose reply is not read yet, in order
  std::deque<flight::FlightOutputs> commands_;  // replies read whose command is not taken yet
  size_t frames_unanswered_ = 0;  // frames sent since the last tick a reply answers
  int frames_found_ = 0;          // frames_detected read, not yet reported to the run
  cv::Rect last_roi_;             // camera_roi of the last reply read
  cv::Rect capture_region_;       // the region of the frame being captured
  ReplyOrder replies_;  // what the stack answered so far: a second reply is refused
};

}  // namespace

std::unique_ptr<FlightLink> MakeInProcessFlight(const flight::FlightConfig& config) {
  return std::make_unique<InProcessFlight>(config);
}

std::unique_ptr<FlightLink> StartExternalFlight(const flight::FlightConfig& config,
                                                const ExternalFlightOptions& options) {
  return std::make_unique<ExternalFlight>(config, options);
}

}  // namespace hpa::runner
