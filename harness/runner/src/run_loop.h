#pragma once
// The lockstep loop of one run (private to the runner): the world, the flight code it drives
// (estimator, controller, rate loop) and the per-tick steps, each a method of its own.

#include <chrono>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "hpa/autopilot/autopilot.h"
#include "hpa/models/lockstep.h"
#include "hpa/models/ring_queue.h"
#include "hpa/scenarios/runner.h"
#include "hpa/sim/world.h"
#include "harness/runner/src/flight_link.h"

namespace hpa::runner {

/// The starting state: payload at the reference's start, hanging at rest under the quadrotor,
/// with the cable length of `params`.
SystemState InitialState(const Reference& reference, const Params& params);

/// Refuses, with an InputError naming the scenario file, the parameter or the reference and the first time it
/// fails, a vehicle that cannot fly the scenario: hover above 80 % of full thrust or idle thrust
/// near the weight, a payload hanging into the body, a body too wide for the arena, or a
/// reference that puts the payload into the ground or the vehicle outside the arena.
void CheckFlyable(const Reference& reference, const Scenario& scenario, const Params& params);

/// The signal a stop was requested with, or 0 (RequestStop sets it).
int StopSignal();

/// The log and metrics inputs of a run (the runner's own recorder).
class LogRecorder final : public RunRecorder {
 public:
  /// Records into `inputs` (not owned).
  explicit LogRecorder(MetricsInputs* inputs) : inputs_(inputs) {}
  void OnControlStep(const LogRow& row) override { inputs_->rows.push_back(row); }
  void OnCameraFrame(const CameraFrameRecord& frame) override;

 private:
  MetricsInputs* inputs_;
};

/// The flight stack's configuration for `scenario` (flight params, not the world's).
flight::FlightConfig FlightConfigOf(const Scenario& scenario, const Params& params,
                                    const SystemState& initial);

/// One run's world, flight code and schedule; Run() steps it tick by tick.
class RunLoop {
 public:
  /// Sets up the world and the flight code of `scenario` (InputError on bad input).
  RunLoop(const Scenario& scenario, const Params& params, const RunOptions& options,
          Metrics* metrics);

  /// Runs to the end, a crash or a stop request; throws what a step throws (the caller keeps
  /// the results so far).
  void Run();

  /// Fills the metrics and log of the run so far (after Run, or after it threw).
  void Finish(RunResult* result);

  /// Simulated time reached (s).
  double time_s() const { return tick_ * sim::World::kPhysicsDt_s; }

 private:
  using Clock = std::chrono::steady_clock;
  // a command between the flight stack and the rate loop
  struct CommandInFlight {
    ControlOutput output;
    bool pending = false;  // on the control thread: taken with AwaitCommand on delivery
  };

  bool Tick();  // one physics tick; false: the run ends here
  void ApplyDueEvents(double t);
  void CameraStep();
  void ReadOutExposure(sim::CameraCapture* capture);
  void KeepTickStartMessage(sim::SensorMessage* message);
  void ControlStep(double t, const sim::Truth& truth, const SystemState& state,
                   const flight::FlightOutputs& out);
  ControlOutput TakeCommand(CommandInFlight* command);
  ControlOutput AwaitPendingCommand(LogRow* row);
  void RateLoopStep(const SystemState& state, bool rate_due);
  void VideoStep(double t, const sim::Truth& truth, const SystemState& state);
  bool StepWorld();  // false: crashed
  void ShowProgress(double t);

  const Scenario& scenario_;
  const Params& params_;
  const RunOptions& options_;
  Metrics* metrics_;
  Clock::time_point wall_start_;
  bool ground_truth_, render_camera_;

  std::unique_ptr<sim::World> world_;
  std::shared_ptr<const Reference> reference_;  // for the log and the metrics
  std::unique_ptr<FlightLink> flight_;          // detector, estimator, controller
  std::unique_ptr<Autopilot> autopilot_;  // the rate loop between the command and the rotors
  // the region of interest a stack that receives every frame asked for with its last reply
  cv::Rect stack_roi_;

  MetricsInputs inputs_;
  LogRecorder log_recorder_{&inputs_};
  std::vector<RunRecorder*> recorders_;

  // schedule
  long tick_ = 0, end_tick_ = 0;
  double end_s_ = 0.0;
  std::unique_ptr<LockstepClock> clock_;
  int rate_loop_ = -1, video_loop_ = -1;
  std::vector<EventSpec> events_;  // by start time
  size_t next_event_ = 0;

  // what is in flight between the loops
  std::unique_ptr<DelayLine<CommandInFlight>> commands_in_flight_;  // compute + transport
  RingQueue<LogRow> rows_awaiting_command_;  // log rows of the pending commands, oldest first
  // the camera's messages delivered by a step, joining the flight stack's inputs at the next
  // tick after that tick's capture (whose region is around the detections delivered before)
  std::vector<PayloadDetection> camera_detections_;
  std::vector<CameraFrame> camera_frames_;
  ControlOutput control_;         // the command the rate loop tracks
  flight::FlightInputs pending_;  // what reaches the flight stack at the next tick

  bool mixer_saturated_ = false;               // the rate loop's last allocation fell short
  std::vector<sim::SensorMessage> delivered_;  // the world's deliveries of one step (reused)
  std::optional<GyroSample> rate_gyro_;        // the rate gyro's newest sample not yet flown on
  bool flown_ = false;  // a control step was logged: the physics-rate extremes count from then
  bool show_progress_ = false;
  int last_progress_pct_ = -1;
};

}  // namespace hpa::runner
