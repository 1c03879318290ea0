#pragma once
// Replay without re-running: a run's chase video (with the onboard inset and the heads-up line)
// rendered after the fact from its log.csv and run.json, so a run found in a sweep can be
// watched without running it again, and nothing about the run changes.

#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "hpa/scenarios/metrics.h"
#include "hpa/sim/gl_backend.h"

namespace hpa {

/// Reads log.csv's rows (time, true and estimated state and mode, command thrust, tension,
/// gripper; the other columns are left default); throws InputError naming the file, line and
/// column for a missing column, a short (truncated) row or a value that is not a number.
std::vector<LogRow> ReadLogCsv(const std::string& path);

/// One rendered frame of a replay.
struct ReplayFrame {
  const LogRow* row = nullptr;  // the logged row it shows (the last at or before its time)
  double time_s = 0.0;          // the video tick
  cv::Mat chase, onboard;       // BGR
};

/// How to replay.
struct ReplayOptions {
  std::string dir;        // a run's folder: run.json and log.csv
  double rate_hz = 30.0;  // video ticks (the run's video rate)
  sim::GlBackend gl_backend = sim::GlBackend::kOsMesa;
  bool progress = false;  // a progress line on stderr
};

/// Rebuilds the run's world from DIR/run.json, sets it to each video tick's logged true state
/// and renders the chase and onboard cameras; calls `on_frame` for each. Returns the number of
/// frames. Throws InputError for a missing or bad run.json or log.csv.
int ReplayRun(const ReplayOptions& options,
              const std::function<void(const ReplayFrame&)>& on_frame);

}  // namespace hpa
