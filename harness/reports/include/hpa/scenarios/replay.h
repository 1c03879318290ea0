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

/// Slack on the run's duration for the last logged time: the log writes times with seven
/// significant digits, which rounds an hour's (the longest scenario) to the millisecond.
constexpr double kLogTimeSlack_s = 1e-3;

/// Reads log.csv's rows (time, true and estimated state and mode, command thrust, tension,
/// gripper; the other columns are left default) from a regular file of bounded size. Throws
/// InputError naming the file, line and column for a missing column, a short (truncated) row, a
/// value that is not a finite number, or a time that is negative, not above the row before or
/// past `duration_s` (plus kLogTimeSlack_s): a log the run of that duration could not have
/// written.
std::vector<LogRow> ReadLogCsv(const std::string& path, double duration_s);

/// One rendered frame of a replay.
struct ReplayFrame {
  const LogRow* row = nullptr;  // the logged row it shows (the last at or before its time)
  double time_s = 0.0;          // the video tick
  cv::Mat chase, onboard;       // BGR
};

/// How to replay.
struct ReplayOptions {
  std::string dir;        // a run's folder: run.json and log.csv
  double rate_hz = 30.0;  // video ticks (the run's video rate), 1 to 1000 (--rate)
  sim::GlBackend gl_backend = sim::GlBackend::kOsMesa;
  bool progress = false;  // a progress line on stderr
};

/// What a replay rendered.
struct ReplaySummary {
  int frames = 0;       // frames rendered (and, for a video, written)
  int stop_signal = 0;  // the signal that stopped it before its end (StopRequested), or 0
  std::string codec;    // ReplayToVideo: the video's codec ("avc1" or "mp4v")
};

/// Rebuilds the run's world from DIR/run.json, sets it to each video tick's logged true state
/// and renders the chase and onboard cameras; calls `on_frame` for each. Polls StopRequested()
/// before each frame and returns early with the signal. Throws InputError for a missing or bad
/// run.json or log.csv, or a rate outside [1, 1000] Hz (named --rate).
ReplaySummary ReplayRun(const ReplayOptions& options,
                        const std::function<void(const ReplayFrame&)>& on_frame);

/// ReplayRun into an MP4 at `video_path` (checked as --out), written whole or not at all: the
/// frames go to PartialPath(video_path), renamed onto it when the last is written. A stop by a
/// signal or an error removes the partial file and leaves any previous video untouched.
/// Throws InputError for bad input, OutputError if the video cannot be written.
ReplaySummary ReplayToVideo(const ReplayOptions& options, const std::string& video_path);

}  // namespace hpa
