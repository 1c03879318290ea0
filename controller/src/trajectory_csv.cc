// The reference CSV reader (reference.h): strict about what it accepts, naming file, line and
// column for what it does not.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>

#include "hpa/controller/reference.h"
#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"

namespace hpa {
namespace {

// The cells of one CSV line, blanks around each trimmed (a trailing comma is an empty cell).
std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream in(line);
  std::string cell;
  while (std::getline(in, cell, ',')) {
    const size_t a = cell.find_first_not_of(" \t\r");
    const size_t b = cell.find_last_not_of(" \t\r");
    cells.push_back(a == std::string::npos ? "" : cell.substr(a, b - a + 1));
  }
  if (!line.empty() && line.back() == ',') cells.push_back("");
  return cells;
}

// Central differences of f over the samples' times (one-sided at the ends).
std::vector<Eigen::Vector3d> Differentiate(const std::vector<TrajectorySample>& s,
                                           Eigen::Vector3d TrajectorySample::*f) {
  const size_t n = s.size();
  std::vector<Eigen::Vector3d> d(n);
  for (size_t i = 0; i < n; ++i) {
    const size_t lo = i == 0 ? 0 : i - 1, hi = i + 1 == n ? n - 1 : i + 1;
    d[i] = (s[hi].*f - s[lo].*f) / (s[hi].t_s - s[lo].t_s);
  }
  return d;
}

// A number as a message shows it (six significant digits).
std::string Num(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

// Whether a CSV line carries no data: blank, or a # comment.
bool IsBlankOrComment(const std::string& line) {
  return line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#';
}

// The header of a reference CSV: where each named column is, and which optional groups it has.
struct CsvHeader {
  std::map<std::string, size_t> column;  // column index by name
  size_t size = 0;                       // number of columns
  bool has_v = false;                    // vx_mps, vy_mps, vz_mps given
  bool has_a = false;                    // ax_mps2, ay_mps2, az_mps2 given
};

// Reads the header line (the first that is neither blank nor a comment; *line_no counts the
// lines read) and checks its columns: known, not repeated, t_s and x/y/z present, the velocity
// and acceleration groups complete or absent.
CsvHeader ReadHeader(std::istream& in, const std::string& path, int* line_no) {
  const std::vector<std::string> known = {"t_s",    "x_m",    "y_m",     "z_m",     "vx_mps",
                                          "vy_mps", "vz_mps", "ax_mps2", "ay_mps2", "az_mps2"};
  std::string line;
  std::vector<std::string> header;
  while (header.empty() && std::getline(in, line)) {
    ++*line_no;
    if (IsBlankOrComment(line)) continue;
    header = SplitCsv(line);
  }
  if (header.empty()) throw InputError(path, "", "empty: expected a header line t_s,x_m,y_m,z_m");
  CsvHeader h;
  h.size = header.size();
  std::map<std::string, size_t>& column = h.column;
  for (size_t c = 0; c < header.size(); ++c) {
    bool ok = false;
    for (const std::string& k : known) ok = ok || header[c] == k;
    if (!ok || column.count(header[c]) > 0) {
      throw InputError(path,
                       "line " + std::to_string(*line_no) + " column " + std::to_string(c + 1),
                       (ok ? "repeated column '" : "unknown column '") + header[c] +
                           "'; columns are t_s, x_m, y_m, z_m, optionally vx_mps, vy_mps, "
                           "vz_mps and ax_mps2, ay_mps2, az_mps2");
    }
    column[header[c]] = c;
  }
  for (const char* need : {"t_s", "x_m", "y_m", "z_m"}) {
    if (column.count(need) == 0) {
      throw InputError(path, "line " + std::to_string(*line_no),
                       std::string("missing column '") + need + "'");
    }
  }
  h.has_v = column.count("vx_mps") && column.count("vy_mps") && column.count("vz_mps");
  h.has_a = column.count("ax_mps2") && column.count("ay_mps2") && column.count("az_mps2");
  if (!h.has_v && (column.count("vx_mps") || column.count("vy_mps") || column.count("vz_mps"))) {
    throw InputError(path, "line " + std::to_string(*line_no),
                     "give all of vx_mps, vy_mps, vz_mps or none");
  }
  if (!h.has_a && (column.count("ax_mps2") || column.count("ay_mps2") || column.count("az_mps2"))) {
    throw InputError(path, "line " + std::to_string(*line_no),
                     "give all of ax_mps2, ay_mps2, az_mps2 or none");
  }
  return h;
}

// One data row as a sample: as many values as the header has columns, each a finite number;
// the velocity and acceleration only when the header has them.
TrajectorySample ParseRow(const std::vector<std::string>& cells, const CsvHeader& header,
                          const PositionRange& range, const std::string& path, int line_no) {
  if (cells.size() != header.size) {
    throw InputError(
        path, "line " + std::to_string(line_no),
        std::to_string(cells.size()) + " values, the header has " + std::to_string(header.size));
  }
  const auto value = [&](const char* name) {
    const size_t c = header.column.at(name);
    char* end = nullptr;
    const double v = std::strtod(cells[c].c_str(), &end);
    if (cells[c].empty() || *end != '\0' || !std::isfinite(v)) {
      throw InputError(path, "line " + std::to_string(line_no) + " column " + std::to_string(c + 1),
                       std::string(name) + ": '" + cells[c] + "' is not a finite number");
    }
    return v;
  };
  TrajectorySample s;
  s.line = line_no;
  s.t_s = value("t_s");
  s.p_WL_W = {value("x_m"), value("y_m"), value("z_m")};
  for (int i = 0; i < 3; ++i) {
    const char* name = i == 0 ? "x_m" : i == 1 ? "y_m" : "z_m";
    if (!(s.p_WL_W(i) >= range.min_m && s.p_WL_W(i) <= range.max_m)) {
      throw InputError(path,
                       "line " + std::to_string(line_no) + " column " +
                           std::to_string(header.column.at(name) + 1),
                       std::string(name) + ": " + cells[header.column.at(name)] +
                           " m is outside the reference positions' range [" + Num(range.min_m) +
                           ", " + Num(range.max_m) + "] m");
    }
  }
  if (header.has_v) s.v_WL_W = {value("vx_mps"), value("vy_mps"), value("vz_mps")};
  if (header.has_a) s.a_WL_W = {value("ax_mps2"), value("ay_mps2"), value("az_mps2")};
  return s;
}

// Checks what the samples imply once their derivatives are filled in: every velocity and
// acceleration finite and every speed at most kMaxTrajectorySpeed_mps; `derived_v` and
// `derived_a` say whether the velocities and accelerations came from central differences (the
// message then names the rows they came from).
void CheckDerivatives(const std::vector<TrajectorySample>& samples, bool derived_v, bool derived_a,
                      const std::string& path) {
  const size_t n = samples.size();
  for (size_t i = 0; i < n; ++i) {
    const TrajectorySample& s = samples[i];
    const std::string line = "line " + std::to_string(s.line);
    // the rows a central difference at row i spans (one-sided at the ends)
    const std::string from = "differenced between lines " +
                             std::to_string(samples[i == 0 ? 0 : i - 1].line) + " and " +
                             std::to_string(samples[i + 1 == n ? n - 1 : i + 1].line);
    if (!s.v_WL_W.allFinite() || !s.a_WL_W.allFinite()) {
      const bool v_bad = !s.v_WL_W.allFinite();
      const bool derived = v_bad ? derived_v : derived_a;
      throw InputError(path, line,
                       std::string(v_bad ? "the velocity" : "the acceleration") + " is not finite" +
                           (derived ? " (" + from + ")" : ""));
    }
    const double speed_mps = s.v_WL_W.norm();
    if (!(speed_mps <= kMaxTrajectorySpeed_mps)) {
      throw InputError(path, line,
                       "a payload speed of " + Num(speed_mps) + " m/s" +
                           (derived_v ? " (" + from + ")" : "") + " is above " +
                           Num(kMaxTrajectorySpeed_mps) +
                           " m/s, faster than the vehicle can fly inside the arena");
    }
  }
}

}  // namespace

std::vector<TrajectorySample> ParseTrajectoryCsv(const std::string& text, const std::string& path,
                                                 const PositionRange& range) {
  // a UTF-8 byte order mark (spreadsheets write one) is not part of the first column's name
  const std::string bom = "\xEF\xBB\xBF";
  std::istringstream in(text.compare(0, bom.size(), bom) == 0 ? text.substr(bom.size()) : text);
  int line_no = 0;
  const CsvHeader header = ReadHeader(in, path, &line_no);
  const std::string t_column = " column " + std::to_string(header.column.at("t_s") + 1);
  std::string line;
  std::vector<TrajectorySample> samples;
  while (std::getline(in, line)) {
    ++line_no;
    if (IsBlankOrComment(line)) continue;
    const std::vector<std::string> cells = SplitCsv(line);
    const TrajectorySample s = ParseRow(cells, header, range, path, line_no);
    if (!samples.empty() && !(s.t_s > samples.back().t_s)) {
      throw InputError(path, "line " + std::to_string(line_no) + t_column,
                       "time " + cells[header.column.at("t_s")] +
                           " s does not increase (the row before: " +
                           std::to_string(samples.back().t_s) + " s)");
    }
    if (!samples.empty() && !(s.t_s - samples.back().t_s >= kMinTrajectoryStep_s)) {
      throw InputError(path, "line " + std::to_string(line_no) + t_column,
                       "time " + cells[header.column.at("t_s")] + " s is " +
                           Num(s.t_s - samples.back().t_s) + " s after the row before (line " +
                           std::to_string(samples.back().line) + "): rows must be at least " +
                           Num(kMinTrajectoryStep_s) +
                           " s apart (a tenth of the 1 ms physics step)");
    }
    samples.push_back(s);
  }
  if (samples.size() < 2) {
    throw InputError(
        path, "", "a reference needs at least two rows, found " + std::to_string(samples.size()));
  }
  if (!header.has_v) {
    const std::vector<Eigen::Vector3d> v = Differentiate(samples, &TrajectorySample::p_WL_W);
    for (size_t i = 0; i < samples.size(); ++i) samples[i].v_WL_W = v[i];
  }
  if (!header.has_a) {
    const std::vector<Eigen::Vector3d> a = Differentiate(samples, &TrajectorySample::v_WL_W);
    for (size_t i = 0; i < samples.size(); ++i) samples[i].a_WL_W = a[i];
  }
  CheckDerivatives(samples, !header.has_v, !header.has_a, path);
  return samples;
}

std::vector<TrajectorySample> LoadTrajectoryCsv(const std::string& path,
                                                const PositionRange& range) {
  return ParseTrajectoryCsv(ReadInputFile(path, "a reference CSV", kMaxReferenceCsvBytes), path,
                            range);
}

void CheckSampledReference(const Params& params, const std::vector<TrajectorySample>& samples,
                           const std::string& file) {
  const std::shared_ptr<Reference> reference = MakeSampledReference(params, samples);
  for (const TrajectorySample& s : samples) {
    const std::string line = "line " + std::to_string(s.line);
    // a is linear between samples: above -g at every sample, above it everywhere
    if (!(s.a_WL_W.z() > -params.gravity_mps2)) {
      throw InputError(file, line,
                       "the payload's vertical acceleration " + Num(s.a_WL_W.z()) +
                           " m/s^2 is at or below free fall (-" + Num(params.gravity_mps2) +
                           " m/s^2): a taut cable cannot hold it, and the quadrotor reference "
                           "(along a + g) is undefined");
    }
    // the reference point as the controller sees it from this sample on (this segment's jerk)
    const ReferencePoint r = reference->At(s.t_s);
    const bool finite = r.p_WL_W.allFinite() && r.v_WL_W.allFinite() && r.a_WL_W.allFinite() &&
                        r.j_WL_W.allFinite() && r.xi_W.allFinite() && r.p_WQ_W.allFinite() &&
                        r.v_WQ_W.allFinite() && r.a_WQ_W.allFinite();
    if (!finite) {
      throw InputError(file, line,
                       "the quadrotor reference derived from this row (differential flatness) is "
                       "not finite: the acceleration changes too fast between rows");
    }
  }
}

}  // namespace hpa
