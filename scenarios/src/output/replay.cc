#include "hpa/scenarios/replay.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "hpa/models/input_error.h"
#include "hpa/scenarios/run_record.h"
#include "hpa/scenarios/runner.h"
#include "hpa/sim/world.h"

namespace hpa {
namespace {

const char* const kStateColumns[kNx] = {"pL_x", "pL_y", "pL_z", "vL_x", "vL_y", "vL_z", "pQ_x",
                                        "pQ_y", "pQ_z", "vQ_x", "vQ_y", "vQ_z", "q_w",  "q_x",
                                        "q_y",  "q_z",  "w_x",  "w_y",  "w_z"};

std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream in(line);
  std::string cell;
  while (std::getline(in, cell, ',')) cells.push_back(cell);
  if (!line.empty() && line.back() == ',') cells.push_back("");
  return cells;
}

}  // namespace

std::vector<LogRow> ReadLogCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "", "cannot open the log");
  std::string line;
  if (!std::getline(in, line)) throw InputError(path, "line 1", "empty: no header");
  const std::vector<std::string> header = Split(line);
  std::map<std::string, size_t> column;
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
  while (std::getline(in, line)) {
    ++line_no;
    const std::vector<std::string> cells = Split(line);
    if (cells.size() != header.size()) {
      throw InputError(path, "line " + std::to_string(line_no),
                       std::to_string(cells.size()) + " fields, the header has " +
                           std::to_string(header.size()) + " (a truncated log?)");
    }
    const auto number = [&](size_t c) {
      char* end = nullptr;
      const double v = std::strtod(cells[c].c_str(), &end);
      if (cells[c].empty() || *end != '\0' || !std::isfinite(v)) {
        throw InputError(path, "line " + std::to_string(line_no) + " column " + header[c],
                         "'" + cells[c] + "' is not a finite number");
      }
      return v;
    };
    LogRow r;
    r.time_s = number(time);
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

int ReplayRun(const ReplayOptions& options,
              const std::function<void(const ReplayFrame&)>& on_frame) {
  const RunRecord record = ReadRunRecord(options.dir);
  const std::vector<LogRow> rows = ReadLogCsv(options.dir + "/log.csv");
  const Scenario scenario = ScenarioOf(record);
  const Params params = ScenarioParams(scenario, record.params);
  sim::World world(WorldConfigOf(scenario, params, options.gl_backend));
  world.Reset(rows.front().truth);
  const InputVector hover = InputVector::Constant(world.world_params().HoverMotorSpeedRadps());
  const bool progress = options.progress && isatty(STDERR_FILENO);
  const double end_s = rows.back().time_s;
  const long ticks = static_cast<long>(std::floor(end_s * options.rate_hz + 1e-9)) + 1;
  size_t next = 0;
  int frames = 0;
  for (long k = 0; k < ticks; ++k) {
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
    world.RenderPayloadCamera(&frame.onboard, cv::Rect());
    frame.chase = world.RenderChaseCamera(960, 540);
    on_frame(frame);
    ++frames;
    if (progress) std::fprintf(stderr, "\rreplay: frame %d / %ld", frames, ticks);
  }
  if (progress) std::fprintf(stderr, "\n");
  return frames;
}

}  // namespace hpa
