#include "hpa/scenarios/replay.h"

#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <string_view>

#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "hpa/scenarios/run_record.h"
#include "hpa/scenarios/runner.h"
#include "hpa/scenarios/video_recorder.h"
#include "hpa/sim/world.h"

namespace hpa {
namespace {

const char* const kStateColumns[kNx] = {"pL_x", "pL_y", "pL_z", "vL_x", "vL_y", "vL_z", "pQ_x",
                                        "pQ_y", "pQ_z", "vQ_x", "vQ_y", "vQ_z", "q_w",  "q_x",
                                        "q_y",  "q_z",  "w_x",  "w_y",  "w_z"};

// The video rates a replay takes (--rate): a frame a second up to the physics rate.
constexpr double kMinRate_Hz = 1.0;
constexpr double kMaxRate_Hz = 1000.0;

// The cells of one CSV line (a trailing comma is an empty last cell); views into `line`.
std::vector<std::string_view> Split(std::string_view line) {
  std::vector<std::string_view> cells;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    cells.push_back(line.substr(start, comma == std::string_view::npos ? comma : comma - start));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return cells;
}

// A number as a message shows it (six significant digits).
std::string Num(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

// Refuses a video rate outside [kMinRate_Hz, kMaxRate_Hz], NaN included.
void CheckRate(double rate_hz) {
  if (!(rate_hz >= kMinRate_Hz && rate_hz <= kMaxRate_Hz)) {
    throw InputError("", "--rate",
                     "'" + Num(rate_hz) + "' is not a video rate: expected frames per second in [" +
                         Num(kMinRate_Hz) + ", " + Num(kMaxRate_Hz) + "]");
  }
}

// A log row's time as a run of duration_s writes it: from 0, after the row before, up to its end;
// an InputError naming the row otherwise.
void CheckRowTime(const std::string& path, const std::string& time_key, double time_s,
                  std::optional<double> previous_s, double duration_s) {
  if (time_s < 0.0) throw InputError(path, time_key, "time " + Num(time_s) + " s is negative");
  if (previous_s && !(time_s > *previous_s)) {
    throw InputError(path, time_key,
                     "time " + Num(time_s) + " s is not after the row before (" +
                         Num(*previous_s) + " s)");
  }
  if (time_s > duration_s + kLogTimeSlack_s) {
    throw InputError(path, time_key,
                     "time " + Num(time_s) + " s is past the run's duration, " + Num(duration_s) +
                         " s (run.json's scenario)");
  }
}

}  // namespace

std::vector<LogRow> ReadLogCsv(const std::string& path, double duration_s) {
  const std::string text = ReadInputFile(path, "a run's log.csv");
  std::string_view rest(text);
  // the next line of the text, without its newline; false at the end
  const auto next_line = [&rest](std::string_view* line) {
    if (rest.empty()) return false;
    const size_t newline = rest.find('\n');
    *line = rest.substr(0, newline);
    rest = newline == std::string_view::npos ? std::string_view() : rest.substr(newline + 1);
    return true;
  };
  std::string_view line;
  if (!next_line(&line)) throw InputError(path, "line 1", "empty: no header");
  const std::vector<std::string_view> header = Split(line);
  std::map<std::string_view, size_t> column;
  for (size_t c = 0; c < header.size(); ++c) column[header[c]] = c;
  const auto index = [&](const std::string& name) {
    const auto it = column.find(name);
    if (it == column.end()) throw InputError(path, "line 1", "no column '" + name + "'");
    return it->second;
  };
  size_t truth[kNx], est[kNx];
  for (int i = 0; i < kNx; ++i) {
    truth[i] = index(std::string("true_") + kStateColumns[i]);
    est[i] = index(std::string("est_") + kStateColumns[i]);
  }
  const size_t time = index("time_s"), true_mode = index("true_mode"), est_mode = index("est_mode"),
               thrust = index("cmd_thrust_N"), tension = index("tension_N"),
               gripper = index("gripper");
  std::vector<LogRow> rows;
  int line_no = 1;
  while (next_line(&line)) {
    ++line_no;
    const std::vector<std::string_view> cells = Split(line);
    const std::string where = "line " + std::to_string(line_no);
    if (cells.size() != header.size()) {
      throw InputError(path, where,
                       std::to_string(cells.size()) + " fields, the header has " +
                           std::to_string(header.size()) + " (a truncated log?)");
    }
    const auto number = [&](size_t c) {
      const std::string_view cell = cells[c];
      double v = 0.0;
      const std::from_chars_result r = std::from_chars(cell.data(), cell.data() + cell.size(), v);
      if (cell.empty() || r.ec != std::errc() || r.ptr != cell.data() + cell.size() ||
          !std::isfinite(v)) {
        throw InputError(path, where + " column " + std::string(header[c]),
                         "'" + std::string(cell) + "' is not a finite number");
      }
      return v;
    };
    LogRow r;
    r.time_s = number(time);
    CheckRowTime(path, where + " column time_s", r.time_s,
                 rows.empty() ? std::nullopt : std::optional<double>(rows.back().time_s),
                 duration_s);
    StateVector xt, xe;
    for (int i = 0; i < kNx; ++i) xt(i) = number(truth[i]), xe(i) = number(est[i]);
    r.truth.FromVector(xt);
    r.estimate.FromVector(xe);
    r.truth.time_s = r.estimate.time_s = r.time_s;
    r.truth.mode = number(true_mode) != 0.0 ? CableMode::kTaut : CableMode::kSlack;
    r.estimate.mode = number(est_mode) != 0.0 ? CableMode::kTaut : CableMode::kSlack;
    r.command.thrust_N = number(thrust);
    r.cable_tension_N = number(tension);
    r.gripper_active = number(gripper) != 0.0;
    rows.push_back(r);
  }
  if (rows.empty()) throw InputError(path, "", "no rows after the header");
  return rows;
}

namespace {

// ReplayRun of a record already read from options.dir/run.json.
ReplaySummary ReplayRecord(const ReplayOptions& options, const RunRecord& record,
                           const std::function<void(const ReplayFrame&)>& on_frame) {
  const Scenario scenario = ScenarioOf(record);
  const std::vector<LogRow> rows = ReadLogCsv(options.dir + "/log.csv", scenario.duration_s);
  ReplaySummary summary;
  if ((summary.stop_signal = StopRequested()) != 0) return summary;
  const Params params = ScenarioParams(scenario, record.params);
  sim::World world(WorldConfigOf(scenario, params, options.gl_backend));
  world.Reset(rows.front().truth);
  const InputVector hover = InputVector::Constant(world.world_params().HoverMotorSpeedRadps());
  const bool progress = options.progress && isatty(STDERR_FILENO);
  // the last time is at most the run's duration (ReadLogCsv), so the frames are bounded by it
  const double end_s = rows.back().time_s;
  const long ticks = static_cast<long>(std::floor(end_s * options.rate_hz + 1e-9)) + 1;
  size_t next = 0;
  for (long k = 0; k < ticks; ++k) {
    // SIGINT / SIGTERM: stop before the next frame
    if ((summary.stop_signal = StopRequested()) != 0) break;
    // the video tick as the live run's clock has it: the physics step nearest k / rate
    const double t =
        std::llround(k / options.rate_hz / sim::World::kPhysicsDt_s) * sim::World::kPhysicsDt_s;
    // the last row at or before the tick; half a physics step of slack absorbs the log's
    // seven-digit times (rows are at least a step apart)
    while (next + 1 < rows.size() && rows[next + 1].time_s <= t + 0.5e-3) ++next;
    const LogRow& row = rows[next];
    world.SetState(row.truth.ToVector(), hover);
    ReplayFrame frame;
    frame.row = &row;
    frame.time_s = t;
    world.renderer().RenderPayloadCamera(&frame.onboard, cv::Rect());
    frame.chase = world.renderer().RenderChaseCamera(960, 540);
    on_frame(frame);
    ++summary.frames;
    if (progress) std::fprintf(stderr, "\rreplay: frame %d / %ld", summary.frames, ticks);
  }
  if (progress) std::fprintf(stderr, "\n");
  return summary;
}

}  // namespace

ReplaySummary ReplayRun(const ReplayOptions& options,
                        const std::function<void(const ReplayFrame&)>& on_frame) {
  CheckRate(options.rate_hz);
  return ReplayRecord(options, ReadRunRecord(options.dir), on_frame);
}

ReplaySummary ReplayToVideo(const ReplayOptions& options, const std::string& video_path) {
  CheckRate(options.rate_hz);
  // a folder that is not a run is refused before the output is looked at
  const RunRecord record = ReadRunRecord(options.dir);
  CheckVideoPath(video_path, "--out");
  // opened at the first frame, after log.csv has been read and checked too
  std::optional<VideoRecorder> video;
  ReplaySummary summary = ReplayRecord(options, record, [&](const ReplayFrame& f) {
    if (!video) video.emplace(video_path, options.rate_hz, false, "--out");
    const VideoRecorder::Hud hud{f.time_s, f.row->truth.mode, f.row->estimate.mode,
                                 f.row->command.thrust_N, f.row->cable_tension_N};
    video->AddFrame(f.chase, f.onboard, hud);
  });
  if (!video) return summary;  // stopped before the first frame: nothing was written
  summary.codec = video->codec();
  if (summary.stop_signal != 0) {
    video->Abandon();  // the previous video stays as it was
    return summary;
  }
  video->Finish();
  return summary;
}

}  // namespace hpa
