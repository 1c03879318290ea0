#pragma once
// The scenario runner: world, flight code and recorders on one lockstep clock (LockstepClock,
// rates and latencies from RateTable: physics 1 kHz, IMU and body-rate loop 500 Hz, VIO and
// camera + detector 30 Hz with their latencies, controller at its registered rate).

#include <functional>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "hpa/models/lockstep.h"
#include "hpa/models/params.h"
#include "hpa/scenarios/metrics.h"
#include "hpa/scenarios/scenario.h"
#include "hpa/sim/gl_backend.h"
#include "hpa/sim/payload_camera.h"
#include "hpa/sim/team_world.h"
#include "hpa/sim/world.h"

namespace hpa {

/// One payload camera frame as the world captured it (sim/payload_camera.h).
using CameraFrameRecord = sim::CameraCapture;

/// Observes a run: the runner calls its recorders from the lockstep loop (its own log,
/// metrics inputs and video are recorders too). Default methods ignore the call.
class RunRecorder {
 public:
  virtual ~RunRecorder() = default;
  /// After each control step, with its log.csv row.
  virtual void OnControlStep(const LogRow& row) { (void)row; }
  /// After each payload camera capture.
  virtual void OnCameraFrame(const CameraFrameRecord& frame) { (void)frame; }
  /// At each video tick with the world to draw from and the HUD values.
  virtual void OnVideoTick(sim::World& world, const LogRow& latest, const cv::Mat& onboard) {
    (void)world, (void)latest, (void)onboard;
  }
  /// At each video tick of a team run, with the team's world to draw from and the latest log row
  /// (none before the first control step).
  virtual void OnTeamVideoTick(sim::TeamWorld& world, const TeamLogRow* latest) {
    (void)world, (void)latest;
  }
  /// The rate (Hz) of video ticks this recorder wants (0: none); the run ticks at the highest
  /// rate any recorder asks for.
  virtual double video_rate_hz() const { return 0.0; }
};

/// How to run (not what: that is the Scenario).
struct RunOptions {
  bool progress = false;                     // progress line on stderr
  std::optional<double> stop_at_s;           // stop early (render-frame)
  std::function<void(sim::World&)> at_stop;  // called with the world when the run stops
  std::vector<RunRecorder*> recorders;       // extra observers, a video among them (not owned)
  sim::GlBackend gl_backend = sim::GlBackend::kOsMesa;  // GL context of the rendered cameras
  // a separate flight stack: the shell command that starts it (empty: the flight stack runs in
  // this process); it speaks the lockstep protocol (docs/protocol.md)
  std::string flight_stack;
  double flight_step_timeout_s = 10.0;  // longest wait for its reply to one tick
  // a team run's separate flight stack: one process per vehicle (true) or one for the team
  bool team_stack_per_vehicle = true;
  // the in-process controller's update on a thread of its own, beside the simulation (the same
  // commands and metrics; a run uses a second core): its log row reaches OnControlStep when its
  // command reaches the rate loop, compute + transport later, rows still in order; a controller
  // that throws ends the run then, not at the tick it was called
  bool control_thread = false;
};

/// The rate table a scenario runs with: the defaults, the scenario's camera latency.
RateTable ScenarioRates(const Scenario& scenario);

/// One loop or sensor stream of a run: how often it fires and how late its output arrives.
struct RateRow {
  std::string name;        // "physics", "imu", "rate loop", "vio", "camera", "control", ...
  double rate_hz = 0.0;    // 0: not periodic (a latency only)
  double latency_s = 0.0;  // capture (or computation) to delivery
  std::string from;        // where the number is set
  std::string noise;       // a sensor's noise ("" for a loop)
};

/// Every loop and stream of `scenario` with the rates and latencies RunScenario uses (the one
/// rate table: `hpa schema rates` prints it).
std::vector<RateRow> ScenarioRateTable(const Scenario& scenario, const Params& params);

/// Everything a run produced.
struct RunResult {
  Metrics metrics;
  std::vector<LogRow> rows;           // a single vehicle's log
  std::vector<TeamLogRow> team_rows;  // a team's log (docs/cooperative.md)
};

/// Writes the run's log.csv: the team's log for a team run, else the single vehicle's.
void WriteRunLogCsv(const std::string& path, const RunResult& result);

/// Async-signal-safe: the running scenario stops at its next physics tick and returns what it
/// has computed, with run_error naming the signal (SIGTERM / SIGINT handlers call this).
void RequestStop(int signal_number);

/// The signal a stop was requested with (RequestStop), or 0.
int StopRequested();

/// Whether RunOptions::control_thread pays on this machine: it has a second core to run on.
bool ControlThreadPays();

/// Runs a scenario to its end (or to a crash, or stop_at_s) and computes its metrics and the
/// expect check; a team scenario runs RunTeamScenario. Throws InputError for bad input found
/// while setting up (MJCF, params).
RunResult RunScenario(const Scenario& scenario, const Params& params, const RunOptions& options);

/// Runs a team scenario (scenario.team: N vehicles on their cables, docs/cooperative.md): the
/// team's world, each vehicle's controller and autopilot, the motion-capture system on one
/// lockstep clock; recorders get OnTeamVideoTick, a separate flight stack the team's messages
/// (docs/protocol.md, "Teams"). Options that need the single vehicle's world (stop_at_s,
/// at_stop) are refused with InputError; the control thread is the single vehicle's.
RunResult RunTeamScenario(const Scenario& scenario, const Params& params,
                          const RunOptions& options);

/// The simulated world of a run of `scenario` with `params` (the flight params: the world adds
/// the scenario's world-only overrides and its profile's mismatch draw).
sim::WorldConfig WorldConfigOf(const Scenario& scenario, const Params& params,
                               sim::GlBackend gl_backend);

/// The world parameters of a scenario: flight params with the scenario's world overrides.
Params WorldParams(const Scenario& scenario, const Params& params);

}  // namespace hpa
