#pragma once
// The deterministic lockstep scheduler: physics 1 kHz, IMU 500 Hz, VIO 30 Hz, camera + detector
// 30 Hz with latency, controller at its rate (150 Hz for the MPCs), body-rate loop 500 Hz.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "hpa/models/params.h"
#include "hpa/scenarios/metrics.h"
#include "hpa/scenarios/scenario.h"

namespace hpa {
namespace sim {
class World;
}

/// How to run (not what: that is the Scenario).
struct RunOptions {
  bool progress = false;                     // progress line on stderr
  std::string video_path;                    // MP4 of the chase camera with the onboard inset
  bool video_slack_events_only = false;      // keep only a window around each slack event
  std::optional<double> stop_at_s;           // stop early (render-frame)
  std::function<void(sim::World&)> at_stop;  // called with the world when the run stops
};

/// Everything a run produced.
struct RunResult {
  Metrics metrics;
  std::vector<LogRow> rows;
};

/// Async-signal-safe: the running scenario stops at its next physics tick and returns what it
/// has computed, with run_error naming the signal (SIGTERM / SIGINT handlers call this).
void RequestStop(int signal_number);

/// Runs a scenario to its end (or to a crash, or stop_at_s) and computes its metrics and the
/// expect check. Throws InputError for bad input found while setting up (MJCF, params).
RunResult RunScenario(const Scenario& scenario, const Params& params, const RunOptions& options);

/// The world parameters of a scenario: flight params with the scenario's world overrides.
Params WorldParams(const Scenario& scenario, const Params& params);

}  // namespace hpa
