#include <sys/stat.h>

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "hpa/models/cooperative_model.h"
#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "hpa/scenarios/metrics.h"

namespace hpa {

void MakeOutputDir(const std::string& dir) {
  std::string partial;
  for (size_t i = 0; i <= dir.size(); ++i) {
    if ((i == dir.size() || dir[i] == '/') && !partial.empty()) mkdir(partial.c_str(), 0755);
    if (i < dir.size()) partial += dir[i];
  }
  struct stat st;
  if (stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) {
    throw OutputError(dir, "cannot create the output folder (--out)");
  }
}

namespace {

// One CSV row formatted into one buffer: std::to_chars with precision 7 writes what
// `out << std::setprecision(7) << value` (printf's %.7g) writes, without the stream's locale and
// formatting machinery on every value.
struct CsvLine {
  std::string line;
  // the value, no separator before it
  void Number(double value) {
    char buf[32];
    const std::to_chars_result r =
        std::to_chars(buf, buf + sizeof buf, value, std::chars_format::general, 7);
    line.append(buf, r.ptr);
  }
  // a separator, then the value
  void Add(double value) {
    line.push_back(',');
    Number(value);
  }
  // a separator, then the integer
  void AddInt(long value) {
    line.push_back(',');
    line += std::to_string(value);
  }
};

// Flushes a log written under PartialPath and renames it into place when whole (CommitPartial):
// a reader never sees half a log; a failed write removes the partial file.
void CloseLog(const std::string& path, std::ofstream* out) {
  out->flush();
  if (!*out) {
    // the failed write's errno (a stream's later operations are no-ops once it has failed):
    // EFBIG names the file-size limit, ENOSPC the full disk
    const int errnum = errno;
    out->close();
    std::remove(PartialPath(path).c_str());
    throw OutputError(path, WriteErrorText(errnum));
  }
  out->close();
  CommitPartial(path);
}

}  // namespace

void WriteLogCsv(const std::string& path, const std::vector<LogRow>& rows) {
  // written under PartialPath and renamed when whole (CommitPartial): a reader never sees half
  // a log
  std::ofstream out(PartialPath(path));
  if (!out) throw OutputError(path, std::strerror(errno));
  auto header_state = [&](const std::string& p) {
    for (const char* n :
         {"pL_x", "pL_y", "pL_z", "vL_x", "vL_y", "vL_z", "pQ_x", "pQ_y", "pQ_z", "vQ_x", "vQ_y",
          "vQ_z", "q_w", "q_x", "q_y", "q_z", "w_x", "w_y", "w_z"}) {
      out << "," << p << n;
    }
    out << "," << p << "mode";
  };
  out << "time_s";
  header_state("true_");
  header_state("est_");
  out << ",ref_pL_x,ref_pL_y,ref_pL_z,ref_pQ_x,ref_pQ_y,ref_pQ_z"
      << ",cmd_w_x,cmd_w_y,cmd_w_z,cmd_thrust_N,status,solve_ms,cost,tension_N,gripper"
      << ",est_rejected_updates,est_resets,mixer_saturated,est_payload_lost,est_payload_"
         "supported\n";
  CsvLine csv;
  std::string& line = csv.line;
  const auto number = [&csv](double value) { csv.Number(value); };
  const auto add = [&csv](double value) { csv.Add(value); };
  const auto add_int = [&csv](long value) { csv.AddInt(value); };
  for (const LogRow& r : rows) {
    line.clear();
    number(r.time_s);
    for (const SystemState* s : {&r.truth, &r.estimate}) {
      const StateVector x = s->ToVector();
      for (int i = 0; i < kNx; ++i) add(x(i));
      add_int(s->mode == CableMode::kTaut ? 1 : 0);
    }
    const auto& ref = r.reference;
    for (int i = 0; i < 3; ++i) add(ref.p_WL_W(i));
    for (int i = 0; i < 3; ++i) add(ref.p_WQ_W(i));
    for (int i = 0; i < 3; ++i) add(r.command.w_B_radps(i));
    add(r.command.thrust_N);
    line.push_back(',');
    line += ToString(r.status);
    add(r.solve_time_ms);
    add(r.cost);
    add(r.cable_tension_N);
    add_int(r.gripper_active ? 1 : 0);
    add_int(r.estimator_rejected_updates);
    add_int(r.estimator_resets);
    add_int(r.mixer_saturated ? 1 : 0);
    add_int(r.estimate.payload_lost ? 1 : 0);
    add_int(r.estimate.payload_supported ? 1 : 0);
    line.push_back('\n');
    out << line;
  }
  CloseLog(path, &out);
}

void WriteTeamLogCsv(const std::string& path, const std::vector<TeamLogRow>& rows, int vehicles) {
  using I = CooperativeStateIndex;
  std::ofstream out(PartialPath(path));
  if (!out) throw OutputError(path, std::strerror(errno));
  const int n = vehicles;
  out << "time_s,true_pL_x,true_pL_y,true_pL_z,true_vL_x,true_vL_y,true_vL_z,true_qP_w,true_qP_x,"
         "true_qP_y,true_qP_z,true_wP_x,true_wP_y,true_wP_z,ref_pL_x,ref_pL_y,ref_pL_z";
  for (int i = 0; i < n; ++i) {
    const std::string v = "v" + std::to_string(i) + "_";
    for (const char* c : {"pQ_x",         "pQ_y",
                          "pQ_z",         "vQ_x",
                          "vQ_y",         "vQ_z",
                          "q_w",          "q_x",
                          "q_y",          "q_z",
                          "w_x",          "w_y",
                          "w_z",          "cable_length_m",
                          "tension_N",    "mode",
                          "taut_seen",    "cmd_w_x",
                          "cmd_w_y",      "cmd_w_z",
                          "cmd_thrust_N", "status",
                          "solve_ms",     "mixer_saturated"}) {
      out << "," << v << c;
    }
  }
  out << "\n";
  CsvLine csv;
  for (const TeamLogRow& r : rows) {
    csv.line.clear();
    csv.Number(r.time_s);
    for (int k = 0; k < I::kBlockSize; ++k) csv.Add(r.x_true(k));
    for (int k = 0; k < 3; ++k) csv.Add(r.reference.p_WL_W(k));
    for (int i = 0; i < n; ++i) {
      const TeamLogRow::Vehicle& v = r.vehicles[static_cast<size_t>(i)];
      for (int k = 0; k < I::kBlockSize; ++k) csv.Add(r.x_true(I::Vehicle(i) + k));
      csv.Add(v.cable_length_m);
      csv.Add(v.cable_tension_N);
      csv.AddInt(v.mode == CableMode::kTaut ? 1 : 0);
      csv.AddInt(v.taut_seen ? 1 : 0);
      for (int k = 0; k < 3; ++k) csv.Add(v.command.w_B_radps(k));
      csv.Add(v.command.thrust_N);
      csv.line.push_back(',');
      csv.line += ToString(v.status);
      csv.Add(v.solve_time_ms);
      csv.AddInt(v.mixer_saturated ? 1 : 0);
    }
    csv.line.push_back('\n');
    out << csv.line;
  }
  CloseLog(path, &out);
}

}  // namespace hpa
