// The reference CSV reader (reference.h): strict about what it accepts, naming file, line and
// column for what it does not.

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "hpa/controller/reference.h"
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
                          const std::string& path, int line_no) {
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
  s.t_s = value("t_s");
  s.p_WL_W = {value("x_m"), value("y_m"), value("z_m")};
  if (header.has_v) s.v_WL_W = {value("vx_mps"), value("vy_mps"), value("vz_mps")};
  if (header.has_a) s.a_WL_W = {value("ax_mps2"), value("ay_mps2"), value("az_mps2")};
  return s;
}

}  // namespace

std::vector<TrajectorySample> LoadTrajectoryCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "", "cannot open the reference CSV");
  int line_no = 0;
  const CsvHeader header = ReadHeader(in, path, &line_no);
  std::string line;
  std::vector<TrajectorySample> samples;
  while (std::getline(in, line)) {
    ++line_no;
    if (IsBlankOrComment(line)) continue;
    const std::vector<std::string> cells = SplitCsv(line);
    const TrajectorySample s = ParseRow(cells, header, path, line_no);
    if (!samples.empty() && !(s.t_s > samples.back().t_s)) {
      throw InputError(path,
                       "line " + std::to_string(line_no) + " column " +
                           std::to_string(header.column.at("t_s") + 1),
                       "time " + cells[header.column.at("t_s")] +
                           " s does not increase (the row before: " +
                           std::to_string(samples.back().t_s) + " s)");
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
  return samples;
}

}  // namespace hpa
