#pragma once
// How the runner reaches the flight stack (private to the runner): in process (the FlightStack
// called directly) or a separate process over the lockstep protocol (the simulator serves a
// Unix socket, starts the command with HPA_FLIGHT_SOCKET set and waits for each reply, so
// simulated time waits for the flight code). Both carry the same messages in the same order.

#include <memory>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>

#include "hpa/flight/protocol.h"
#include "harness/runner/src/stack_process.h"

namespace hpa::runner {

/// What a flight stack reports at the end of a run.
struct FlightFinish {
  std::string estimator;                  // its estimator ("" with ground truth)
  flight::HealthFields estimator_health;  // its estimator's counters
  int frames_detected = 0;  // of the frames captured but not delivered, with the payload
};

/// The rendered-camera frames a separate flight stack reads: a shared-memory ring.
struct FrameRingSpec {
  int slots = 0;  // 0: no frames cross (analytic camera, ground truth, or in process)
  int width_px = 0, height_px = 0;
};

/// One run's connection to its flight stack.
class FlightLink {
 public:
  virtual ~FlightLink() = default;
  /// One tick (FlightStack::Step).
  virtual flight::FlightOutputs Step(const flight::FlightInputs& in) = 0;
  /// The command of the oldest control step that answered command_pending (waits for it).
  virtual ControlOutput AwaitCommand() {
    throw std::logic_error("this flight stack answers every command at its step");
  }
  /// The reply of the oldest control step that answered command_pending (waits for it): its
  /// command and, when the step's estimate and estimator health came with it rather than at
  /// its step (a separate stack's batched ticks), those too (has_estimate).
  virtual flight::FlightOutputs AwaitReply() {
    flight::FlightOutputs out;
    out.has_command = true;
    out.command = AwaitCommand();
    return out;
  }
  /// Whether the stack reads each rendered frame at its capture (CaptureRegion, DetectCaptured)
  /// instead of receiving every whole frame.
  virtual bool detects_at_capture() const { return false; }
  /// The region of the frame captured now that the stack reads first (empty: the whole frame).
  virtual cv::Rect CaptureRegion() { return cv::Rect(); }
  /// The stack's detection in the frame captured now (its region read out, if it has one),
  /// reading the whole frame of the same exposure with `read_whole` only when the stack asks.
  virtual PayloadDetection DetectCaptured(const CameraFrame& frame,
                                          const WholeFrameReader& read_whole) {
    (void)frame;
    (void)read_whole;
    throw std::logic_error("this flight stack does not detect at capture");
  }
  /// Whether the stack reads rendered frames: false for a separate stack that declared
  /// uses_pixels false in its hello_ack (it is sent none, and the run renders none for it).
  virtual bool uses_pixels() const { return true; }
  /// Whether the stack runs the vehicle's rate loop (declared owns_rate_loop in its hello_ack):
  /// the runner then runs no autopilot and asks RateLoop at each of the loop's steps.
  virtual bool owns_rate_loop() const { return false; }
  /// One step of the stack's own rate loop: its rotor speed commands and allocation report,
  /// checked (finite, inside the motors' range).
  virtual AutopilotOutput RateLoop(const flight::RateTick& tick) {
    (void)tick;
    throw std::logic_error("this flight stack does not own the rate loop");
  }
  /// Ends the run: hands the stack the inputs still pending and returns its final report.
  virtual FlightFinish Finish(const flight::FlightInputs& pending) = 0;
  /// The next frame-ring slot to render into (its index in *slot); nullptr: frames do not
  /// cross (the runner detects in process).
  virtual cv::Mat* NextFrameSlot(int* slot) {
    (void)slot;
    return nullptr;
  }
  /// Whether the stack is a separate process (it reads the per-tick reference sample and, unless
  /// it detects at capture, every rendered frame).
  virtual bool wants_reference() const { return false; }
  /// What flies: "in_process" or the name the separate stack gave in its hello.
  virtual std::string name() const = 0;
  /// The controller that flies, for metrics.json's controller: the scenario's in process; a
  /// separate stack's hello_ack `controller`, else its name (it flies its own controller).
  virtual std::string controller() const = 0;
  /// The stack's control rate (Hz) as it states it (a separate stack in its hello_ack; 0: not
  /// stated): information for sizing the log, the stack decides when it commands.
  virtual double control_rate_hz() const = 0;
};

/// The flight stack in this process.
std::unique_ptr<FlightLink> MakeInProcessFlight(const flight::FlightConfig& config);

/// Settings of a separate flight stack.
struct ExternalFlightOptions {
  std::string command;           // shell command line that starts it
  double step_timeout_s = 10.0;  // longest wait for one whole message (reply, hello_ack)
  double connect_timeout_s = kConnectTimeoutS;  // longest wait for it to connect
  FrameRingSpec frames;                         // the rendered camera's frames, if they cross
  nlohmann::json rates;                         // the rate table, for the hello
  std::string scenario;                         // the scenario's name and seed, for the hello
  unsigned long seed = 0;
  flight::RateLoopConfig rate_loop;  // the vehicle's rate loop, for a stack that owns it
};

/// Starts `options.command` and completes the hello; throws flight::ProtocolError naming the
/// command for one that does not start, connect, or speak this protocol's version, and
/// flight::WaitInterrupted naming the signal when a stop (StopRequested) ends the wait. Every
/// wait on the stack polls StopRequested; every reply is checked at this boundary
/// (flight::DecodeReply, CheckReply, ParseHelloAck, ParseFinishReply): a stack's bad value ends
/// the run with a run error naming it.
std::unique_ptr<FlightLink> StartExternalFlight(const flight::FlightConfig& config,
                                                const ExternalFlightOptions& options);

}  // namespace hpa::runner
