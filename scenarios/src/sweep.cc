#include "hpa/scenarios/sweep.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <set>
#include <sstream>
#include <thread>

#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/models/yaml_reader.h"
#include "hpa/scenarios/plot_canvas.h"
#include "hpa/scenarios/runner.h"
#include "hpa/scenarios/scenario.h"

namespace hpa {
namespace {

using Json = nlohmann::ordered_json;

// Takes an exclusive lock on an output folder for the life of this process: two sweeps writing
// one runs.jsonl would record every run twice. A second sweep is refused, naming the holder.
void LockOutputDir(const std::string& dir) {
  const std::string path = dir + "/.lock";
  const int fd = open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw InputError(path, "--out", std::string("cannot open: ") + std::strerror(errno));
  if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
    char holder[32] = {0};
    const ssize_t n = pread(fd, holder, sizeof(holder) - 1, 0);
    close(fd);
    throw InputError(dir, "--out",
                     "another hpa sweep (pid " + std::string(n > 0 ? holder : "?") +
                         ") is writing to this folder; wait for it or use another --out");
  }
  const std::string pid = std::to_string(getpid());
  if (ftruncate(fd, 0) != 0 || pwrite(fd, pid.c_str(), pid.size(), 0) < 0) {
    throw InputError(path, "--out", std::string("cannot write: ") + std::strerror(errno));
  }
  // kept open (and locked) until the process exits
}

// A sweep killed mid-write leaves an unterminated last line; appending after it would glue the
// next record onto it. Cut it off (its run has no record and runs again) and say so.
void DropTornLastLine(const std::string& jsonl) {
  std::ifstream in(jsonl, std::ios::binary);
  if (!in) return;
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (text.empty() || text.back() == '\n') return;
  const size_t keep = text.rfind('\n') == std::string::npos ? 0 : text.rfind('\n') + 1;
  if (truncate(jsonl.c_str(), static_cast<off_t>(keep)) != 0) {
    throw InputError(jsonl, "", std::string("cannot repair: ") + std::strerror(errno));
  }
  std::fprintf(stderr,
               "hpa: %s ended in an unterminated line (a sweep killed mid-write): dropped %zu "
               "bytes; that run will be run again\n",
               jsonl.c_str(), text.size() - keep);
}

// Writes a file whole and checks it reached the disk (a full disk is an error, not silence).
void WriteFileChecked(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::trunc);
  out << text;
  out.flush();
  if (!out) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
}

using Clock = std::chrono::steady_clock;

// SplitMix64: derives independent seeds from the sweep seed (stable across platforms).
uint64_t SplitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "", "cannot open file");
  return std::string(std::istreambuf_iterator<char>(in), {});
}

std::string Hex(uint64_t v) {
  std::ostringstream out;
  out << std::hex << std::setw(16) << std::setfill('0') << v;
  return out.str();
}

// FNV-1a of a text: identifies a sweep (its file and its base scenario's text).
uint64_t Fnv1a(const std::string& text) {
  uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ULL;
  return h;
}

std::string FormatNumber(double v) {
  std::ostringstream out;
  out << std::setprecision(17) << v;
  return out.str();
}

bool IsNumber(const std::string& s, double* v = nullptr) {
  char* end = nullptr;
  const double d = std::strtod(s.c_str(), &end);
  if (s.empty() || *end != '\0' || !std::isfinite(d)) return false;
  if (v) *v = d;
  return true;
}

std::string Dirname(const std::string& path) {
  const size_t slash = path.rfind('/');
  return slash == std::string::npos ? "." : path.substr(0, slash);
}

// Builds the scenario of one run: the base file with the run's values set, validated.
Scenario BuildScenario(const SweepSpec& spec, const SweepRun& run) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(spec.base_path);
  } catch (const YAML::Exception& e) {
    throw InputError(spec.base_path, "", std::string("malformed YAML: ") + e.what());
  }
  for (const auto& [path, value] : run.values) SetDottedPath(root, path, value, spec.file);
  Scenario s = ParseScenario(YamlMap(root, spec.base_path, ""));
  s.seed = run.seed;
  return s;
}

// One parsed line of runs.jsonl.
struct Record {
  int run = -1;
  unsigned long seed = 0;
  std::string sweep_id, sweep_file, base;
  std::vector<std::pair<std::string, std::string>> values;
  std::string controller;
  bool error = false;
  std::string error_text;
  bool crashed = false;
  bool expect_failed = false;  // any `expect` bound of the scenario failed (crash included)
  double payload_rmse_norm_m = 0, quad_dev_max_m = 0, solve_median_ms = 0, slack_time_s = 0;
  double payload_in_fov = 1;
  std::string line;  // the raw JSON line
};

std::vector<Record> ReadRecords(const std::string& path) {
  std::vector<Record> out;
  std::ifstream in(path);
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty()) continue;
    Record r;
    r.line = line;
    try {
      const Json n = Json::parse(line);
      r.run = n.at("run").get<int>();
      r.seed = n.at("seed").get<unsigned long>();
      r.sweep_id = n.at("sweep_id").get<std::string>();
      r.sweep_file = n.at("sweep").get<std::string>();
      r.base = n.at("base").get<std::string>();
      for (const auto& [key, value] : n.at("values").items()) {
        r.values.emplace_back(key, value.is_string() ? value.get<std::string>() : value.dump());
      }
      r.controller = n.at("controller").get<std::string>();
      r.error = n.at("status").get<std::string>() != "ok";
      if (r.error) {
        r.error_text = n.at("error").is_string() ? n.at("error").get<std::string>() : "";
      } else {
        const Json& m = n.at("metrics");
        const auto number = [](const Json& v) {
          return v.is_number() ? v.get<double>() : std::nan("");
        };
        r.crashed = m.at("crashed").get<bool>();
        r.expect_failed = !m.at("expect").at("passed").get<bool>();
        const Json& e = m.at("payload_rmse_m");
        r.payload_rmse_norm_m =
            std::sqrt(std::pow(number(e.at(0)), 2) + std::pow(number(e.at(1)), 2) +
                      std::pow(number(e.at(2)), 2));
        r.quad_dev_max_m = number(m.at("quad_position_deviation_max_m"));
        r.solve_median_ms = number(m.at("mpc_solve_ms").at("median"));
        r.slack_time_s = number(m.at("slack_time_s"));
        r.payload_in_fov = number(m.at("payload_in_fov_fraction"));
      }
    } catch (const Json::exception& e) {
      // a torn last line (the sweep was killed mid-write) is skipped; it will be re-run
      std::fprintf(stderr, "hpa: warning: %s:%d: unreadable line skipped (%s)\n", path.c_str(),
                   line_no, e.what());
      continue;
    }
    out.push_back(r);
  }
  return out;
}

// Wilson score interval for k successes in n trials (95 %).
std::pair<double, double> Wilson(int k, int n) {
  if (n == 0) return {0.0, 1.0};
  const double z = 1.959963984540054, p = static_cast<double>(k) / n;
  const double denom = 1 + z * z / n;
  const double centre = (p + z * z / (2 * n)) / denom;
  const double half = z * std::sqrt(p * (1 - p) / n + z * z / (4.0 * n * n)) / denom;
  return {std::max(0.0, centre - half), std::min(1.0, centre + half)};
}

std::string Fixed(double v, int decimals = 3) {
  if (!std::isfinite(v)) return "-";
  std::ostringstream out;
  out << std::fixed << std::setprecision(decimals) << v;
  return out.str();
}

// Writes summary.json, summary.md and crash_rate.png from the records of one sweep.
void WriteSummary(const std::vector<Record>& records, const std::string& dir) {
  // the main varied quantity: the first numeric vary path that is not the controller type
  std::string main_path;
  for (const Record& r : records) {
    for (const auto& [path, value] : r.values) {
      if (path != "controller.type" && IsNumber(value) && main_path.empty()) main_path = path;
    }
    if (!main_path.empty()) break;
  }
  auto main_value = [&](const Record& r) {
    for (const auto& [path, value] : r.values) {
      double v;
      if (path == main_path && IsNumber(value, &v)) return v;
    }
    return 0.0;
  };

  // bins over the main quantity: its distinct values if few, else 6 equal-width bins
  std::set<double> distinct;
  for (const Record& r : records) distinct.insert(main_value(r));
  std::vector<std::pair<double, double>> bins;  // [lo, hi]
  if (distinct.size() <= 8) {
    for (double v : distinct) bins.emplace_back(v, v);
  } else {
    const double lo = *distinct.begin(), hi = *distinct.rbegin();
    for (int i = 0; i < 6; ++i) {
      bins.emplace_back(lo + (hi - lo) * i / 6.0, lo + (hi - lo) * (i + 1) / 6.0);
    }
  }
  auto bin_of = [&](double v) {
    for (size_t i = 0; i < bins.size(); ++i) {
      if (v >= bins[i].first - 1e-12 && v <= bins[i].second + 1e-12) return static_cast<int>(i);
    }
    return static_cast<int>(bins.size()) - 1;
  };

  std::set<std::string> controllers;
  for (const Record& r : records) controllers.insert(r.controller);

  struct Cell {
    int n = 0, crashes = 0, errors = 0, expect_failures = 0;
    std::vector<double> rmse, dev, solve;
  };
  std::map<std::string, Cell> total;
  std::map<std::string, std::vector<Cell>> per_bin;
  for (const auto& c : controllers) per_bin[c].resize(bins.size());
  for (const Record& r : records) {
    for (Cell* cell : {&total[r.controller], &per_bin[r.controller][bin_of(main_value(r))]}) {
      if (r.error) {
        ++cell->errors;
        continue;
      }
      ++cell->n;
      if (r.crashed) ++cell->crashes;
      if (r.expect_failed) ++cell->expect_failures;
      if (!r.crashed) cell->rmse.push_back(r.payload_rmse_norm_m);
      cell->dev.push_back(r.quad_dev_max_m);
      cell->solve.push_back(r.solve_median_ms);
    }
  }

  // summary.json (non-finite values, e.g. quantiles of no run, are null)
  const auto num = [](double v) { return std::isfinite(v) ? Json(v) : Json(); };
  Json summary;
  summary["runs"] = records.size();
  summary["main_varied"] = main_path;
  summary["controllers"] = Json::object();
  for (const auto& c : controllers) {
    const Cell& t = total[c];
    const auto ci = Wilson(t.crashes, t.n);
    Json entry = {
        {"runs", t.n},
        {"errors", t.errors},
        {"crashes", t.crashes},
        {"crash_rate", t.n ? num(static_cast<double>(t.crashes) / t.n) : Json()},
        {"crash_rate_ci95", {num(ci.first), num(ci.second)}},
        {"expect_failures", t.expect_failures},
        {"payload_rmse_norm_m",
         {{"median", num(Quantile(t.rmse, 0.5))}, {"p90", num(Quantile(t.rmse, 0.9))}}},
        {"quad_deviation_max_m",
         {{"median", num(Quantile(t.dev, 0.5))}, {"p90", num(Quantile(t.dev, 0.9))}}},
        {"mpc_solve_median_ms",
         {{"median", num(Quantile(t.solve, 0.5))}, {"p99", num(Quantile(t.solve, 0.99))}}},
        {"bins", Json::array()}};
    for (size_t b = 0; b < bins.size(); ++b) {
      const Cell& cell = per_bin[c][b];
      const auto bci = Wilson(cell.crashes, cell.n);
      entry["bins"].push_back(
          {{"lo", num(bins[b].first)},
           {"hi", num(bins[b].second)},
           {"runs", cell.n},
           {"crashes", cell.crashes},
           {"crash_rate", cell.n ? num(static_cast<double>(cell.crashes) / cell.n) : Json()},
           {"ci95", {num(bci.first), num(bci.second)}},
           {"expect_failures", cell.expect_failures}});
    }
    summary["controllers"][c] = entry;
  }
  WriteFileChecked(dir + "/summary.json", summary.dump(2) + "\n");

  // summary.md
  std::ostringstream md;
  md << "# Sweep summary\n\n" << records.size() << " runs";
  if (!records.empty())
    md << " of `" << records.front().sweep_file << "` (base `" << records.front().base << "`)";
  md << ". Crash rates with 95 % Wilson intervals; RMSE is the norm of the per-axis payload RMSE "
        "over runs that did not crash.\n\n";
  md << "| controller | runs | errors | crashes | crash rate [95% CI] | expect failures [95% CI] | "
        "payload RMSE median / p90 [m] | quad deviation median / p90 [m] | solve median [ms] "
        "|\n|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& c : controllers) {
    const Cell& t = total[c];
    const auto ci = Wilson(t.crashes, t.n);
    md << "| " << c << " | " << t.n << " | " << t.errors << " | " << t.crashes << " | "
       << Fixed(t.n ? 1.0 * t.crashes / t.n : 0.0, 3) << " [" << Fixed(ci.first, 3) << ", "
       << Fixed(ci.second, 3) << "] | " << t.expect_failures << "/" << t.n << " ["
       << Fixed(Wilson(t.expect_failures, t.n).first, 3) << ", "
       << Fixed(Wilson(t.expect_failures, t.n).second, 3) << "] | " << Fixed(Quantile(t.rmse, 0.5))
       << " / " << Fixed(Quantile(t.rmse, 0.9)) << " | " << Fixed(Quantile(t.dev, 0.5)) << " / "
       << Fixed(Quantile(t.dev, 0.9)) << " | " << Fixed(Quantile(t.solve, 0.5)) << " |\n";
  }
  if (!main_path.empty()) {
    md << "\n## Crash rate (and expect-failure count) against `" << main_path << "`\n\n| bin |";
    for (const auto& c : controllers) md << " " << c << " |";
    md << "\n|---|";
    for (size_t i = 0; i < controllers.size(); ++i) md << "---|";
    md << "\n";
    for (size_t b = 0; b < bins.size(); ++b) {
      md << "| " << Fixed(bins[b].first)
         << (bins[b].first == bins[b].second ? "" : " - " + Fixed(bins[b].second)) << " |";
      for (const auto& c : controllers) {
        const Cell& cell = per_bin[c][b];
        const auto ci = Wilson(cell.crashes, cell.n);
        md << " " << cell.crashes << "/" << cell.n << " [" << Fixed(ci.first, 2) << ", "
           << Fixed(ci.second, 2) << "] (expect failed " << cell.expect_failures << ") |";
      }
      md << "\n";
    }
  }
  // worst runs, with the command that replays each exactly
  std::vector<const Record*> worst;
  for (const Record& r : records) worst.push_back(&r);
  std::sort(worst.begin(), worst.end(), [](const Record* a, const Record* b) {
    if (a->error != b->error) return a->error;
    if (a->crashed != b->crashed) return a->crashed;
    return a->quad_dev_max_m > b->quad_dev_max_m;
  });
  md << "\n## Worst runs (errors, crashes, then largest quadrotor deviation)\n\n";
  for (size_t i = 0; i < std::min<size_t>(8, worst.size()); ++i) {
    const Record& r = *worst[i];
    md << "- run " << r.run << " (" << r.controller << "): "
       << (r.error ? "ERROR " + r.error_text
                   : (r.crashed ? std::string("crashed") : std::string("ok")) +
                         ", quad deviation " + Fixed(r.quad_dev_max_m) + " m")
       << "\n  `hpa run " << r.base << " --seed " << r.seed;
    for (const auto& [path, value] : r.values) md << " --set " << path << "=" << value;
    md << "`\n";
  }
  std::ofstream(dir + "/summary.md") << md.str();

  // crash rate plot, one line per controller
  if (!main_path.empty()) {
    cv::Mat fig = BlankFigure(1000, 600);
    PlotPanel p(&fig, cv::Rect(0, 0, 1000, 600),
                "crash rate (thick, 95% Wilson CI) and expect-failure rate (thin)", main_path,
                "rate");
    double x0 = bins.front().first, x1 = bins.back().second;
    if (x1 <= x0) x1 = x0 + 1;
    const double pad = 0.05 * (x1 - x0);
    p.SetRange(x0 - pad, x1 + pad, -0.02, 1.02);
    p.DrawAxes();
    std::vector<std::pair<std::string, cv::Scalar>> legend;
    int k = 0;
    for (const auto& c : controllers) {
      std::vector<double> x, y, lo, hi, fail;
      for (size_t b = 0; b < bins.size(); ++b) {
        const Cell& cell = per_bin[c][b];
        if (cell.n == 0) continue;
        const auto ci = Wilson(cell.crashes, cell.n);
        x.push_back(0.5 * (bins[b].first + bins[b].second));
        y.push_back(1.0 * cell.crashes / cell.n);
        lo.push_back(ci.first);
        hi.push_back(ci.second);
        fail.push_back(1.0 * cell.expect_failures / cell.n);
      }
      p.Line(x, fail, SeriesColour(k), 1);
      p.Line(x, y, SeriesColour(k), 2);
      p.ErrorBars(x, y, lo, hi, SeriesColour(k));
      legend.emplace_back(c, SeriesColour(k));
      ++k;
    }
    p.Legend(legend);
    cv::imwrite(dir + "/crash_rate.png", fig);
  }
}

// One JSON line of runs.jsonl: the run's identity and values, then its outcome. `metrics_json`
// empty means none; `error` empty means the run finished.
std::string RecordLine(const SweepSpec& spec, const SweepRun& run, const std::string& controller,
                       const std::string& error, const std::string& metrics_json) {
  Json line;
  line["sweep_id"] = spec.sweep_id;
  line["sweep"] = spec.file;
  line["base"] = spec.base_path;
  line["run"] = run.index;
  line["draw"] = run.draw;
  line["seed"] = run.seed;
  line["values"] = Json::object();
  for (const auto& [path, value] : run.values) {
    double number = 0.0;
    line["values"][path] = IsNumber(value, &number) ? Json(number) : Json(value);
  }
  line["controller"] = controller;
  line["status"] = error.empty() ? "ok" : "error";
  line["error"] = error.empty() ? Json() : Json(error);
  line["metrics"] = metrics_json.empty() ? Json() : Json::parse(metrics_json);
  // one line, invalid UTF-8 in names or messages replaced rather than thrown on
  return line.dump(-1, ' ', false, Json::error_handler_t::replace);
}

// The controller type of a run (for records of runs whose process died).
std::string ControllerOf(const SweepSpec& spec, const SweepRun& run) {
  try {
    return BuildScenario(spec, run).controller.type;
  } catch (const std::exception&) {
    return "?";
  }
}

// Runs one sweep run in this (child) process and returns its JSON line.
std::string RunOne(const SweepSpec& spec, const SweepRun& run, const Params& params) {
  std::string controller = "?";
  try {
    const Scenario scenario = BuildScenario(spec, run);
    controller = scenario.controller.type;
    const RunResult result = RunScenario(scenario, params, RunOptions{});
    const std::string metrics = MetricsToJson(result.metrics);
    return RecordLine(spec, run, controller, result.metrics.run_error.value_or(""), metrics);
  } catch (const std::exception& e) {
    return RecordLine(spec, run, controller, e.what(), "");
  }
}

}  // namespace

void SetDottedPath(YAML::Node root, const std::string& path, const std::string& value,
                   const std::string& file) {
  std::vector<std::string> parts;
  std::stringstream ss(path);
  for (std::string p; std::getline(ss, p, '.');) parts.push_back(p);
  if (parts.empty()) throw InputError(file, path, "empty key path");
  // walk with node handles; yaml-cpp nodes are references into the tree
  std::vector<YAML::Node> chain{root};
  std::string walked;
  for (size_t i = 0; i + 1 < parts.size(); ++i) {
    YAML::Node cur = chain.back();
    walked += (walked.empty() ? "" : ".") + parts[i];
    YAML::Node next;
    if (cur.IsSequence()) {
      double idx;
      if (!IsNumber(parts[i], &idx) || idx < 0 || idx >= cur.size() || idx != std::floor(idx)) {
        throw InputError(file, path,
                         "'" + walked + "' is not an index of the list (size " +
                             std::to_string(cur.size()) + ")");
      }
      next = cur[static_cast<size_t>(idx)];
    } else if (cur.IsMap()) {
      if (!cur[parts[i]]) {
        if (IsNumber(parts[i + 1])) {
          throw InputError(file, path,
                           "'" + walked + "' is not in the base scenario, so '" + parts[i + 1] +
                               "' is not an index of a list");
        }
        cur[parts[i]] = YAML::Node(YAML::NodeType::Map);
      }
      next = cur[parts[i]];
    } else {
      throw InputError(file, path, "'" + walked + "' is not a map or a list in the base scenario");
    }
    chain.push_back(next);
  }
  YAML::Node parent = chain.back();
  const std::string& last = parts.back();
  if (parent.IsSequence()) {
    double idx;
    if (!IsNumber(last, &idx) || idx < 0 || idx >= parent.size()) {
      throw InputError(file, path, "'" + last + "' is not an index of the list");
    }
    parent[static_cast<size_t>(idx)] = YAML::Load(value);
  } else if (parent.IsMap() || parent.IsNull()) {
    parent[last] = YAML::Load(value);
  } else {
    throw InputError(file, path, "parent of the last key is a scalar in the base scenario");
  }
}

SweepSpec LoadSweep(const std::string& path) {
  const YamlMap root = YamlMap::LoadFile(path);
  SweepSpec s;
  s.file = path;
  const std::string base = root.String("base");
  s.base_path = (!base.empty() && base[0] == '/') ? base : Dirname(path) + "/" + base;
  s.runs = static_cast<int>(root.Integer("runs", 1, 1000000));
  s.seed = static_cast<unsigned long>(root.Integer("seed", 0, 4294967295L, 1));
  s.time_limit_s = root.Number("time_limit", 1.0, 1e6, 600.0);
  if (root.Has("vary")) {
    const YamlMap vary = root.Map("vary");
    const YAML::Node node = root.Node("vary");
    for (const auto& kv : node) {
      VarySpec v;
      v.path = kv.first.as<std::string>();
      if (v.path == "seed") {
        vary.Fail("seed",
                  "the seed cannot be varied: each run's seed is drawn from the sweep's "
                  "`seed`");
      }
      const YamlMap d = vary.Map(v.path);
      const std::vector<std::string> kinds = {"uniform", "normal", "grid", "list"};
      int found = 0;
      for (const auto& k : kinds) found += d.Has(k) ? 1 : 0;
      if (found != 1) d.Fail("", "expected exactly one of uniform | normal | grid | list");
      if (d.Has("uniform")) {
        const Eigen::VectorXd ab = d.Vector("uniform", 2, -1e9, 1e9);
        if (ab(1) < ab(0)) d.Fail("uniform", "expected [low, high] with low <= high");
        v.kind = VarySpec::Kind::kUniform, v.a = ab(0), v.b = ab(1);
      } else if (d.Has("normal")) {
        const Eigen::VectorXd ab = d.Vector("normal", 2, -1e9, 1e9);
        if (ab(1) < 0) d.Fail("normal", "expected [mean, sigma] with sigma >= 0");
        v.kind = VarySpec::Kind::kNormal, v.a = ab(0), v.b = ab(1);
      } else {
        const std::string key = d.Has("grid") ? "grid" : "list";
        v.kind = key == "grid" ? VarySpec::Kind::kGrid : VarySpec::Kind::kList;
        const YAML::Node list = d.Node(key);
        if (!list.IsSequence() || list.size() == 0) d.Fail(key, "expected a non-empty list");
        for (const auto& item : list) {
          if (!item.IsScalar()) d.Fail(key, "expected a list of scalars");
          v.values.push_back(item.as<std::string>());
        }
      }
      d.RejectUnknownKeys();
      s.vary.push_back(v);
    }
  }
  root.RejectUnknownKeys();
  s.sweep_id = Hex(Fnv1a(ReadFile(path) + "\n--base--\n" + ReadFile(s.base_path)));

  // validate every path against the base scenario before anything runs (first value of each)
  SweepRun probe;
  for (const VarySpec& v : s.vary) {
    const std::string value = v.values.empty() ? FormatNumber(v.a) : v.values.front();
    probe.values.emplace_back(v.path, value);
  }
  try {
    BuildScenario(s, probe);
    // every grid and list value must be valid too
    for (size_t i = 0; i < s.vary.size(); ++i) {
      for (const std::string& value : s.vary[i].values) {
        SweepRun one = probe;
        one.values[i].second = value;
        BuildScenario(s, one);
      }
    }
  } catch (const InputError& e) {
    throw InputError(path, "vary",
                     std::string("applying the vary paths to the base scenario: ") + e.what());
  }
  return s;
}

std::vector<SweepRun> ExpandSweep(const SweepSpec& spec) {
  // grid cells: the cartesian product of every grid entry, in file order
  std::vector<std::vector<std::pair<std::string, std::string>>> cells{{}};
  for (const VarySpec& v : spec.vary) {
    if (v.kind != VarySpec::Kind::kGrid) continue;
    std::vector<std::vector<std::pair<std::string, std::string>>> next;
    for (const auto& cell : cells) {
      for (const auto& value : v.values) {
        auto c = cell;
        c.emplace_back(v.path, value);
        next.push_back(c);
      }
    }
    cells = next;
  }
  std::vector<SweepRun> runs;
  for (int d = 0; d < spec.runs; ++d) {
    // each draw has its own generator: its values do not depend on the other draws
    const uint64_t draw_seed = SplitMix64(spec.seed * 1000003ULL + static_cast<uint64_t>(d));
    std::mt19937_64 rng(draw_seed);
    std::vector<std::pair<std::string, std::string>> drawn;
    for (const VarySpec& v : spec.vary) {
      switch (v.kind) {
        case VarySpec::Kind::kUniform:
          drawn.emplace_back(v.path,
                             FormatNumber(std::uniform_real_distribution<double>(v.a, v.b)(rng)));
          break;
        case VarySpec::Kind::kNormal:
          drawn.emplace_back(
              v.path,
              FormatNumber(v.b > 0 ? std::normal_distribution<double>(v.a, v.b)(rng) : v.a));
          break;
        case VarySpec::Kind::kList:
          drawn.emplace_back(v.path, v.values[d % v.values.size()]);
          break;
        case VarySpec::Kind::kGrid:
          break;
      }
    }
    for (size_t g = 0; g < cells.size(); ++g) {
      SweepRun r;
      r.index = static_cast<int>(d * cells.size() + g);
      r.draw = d;
      r.seed = static_cast<unsigned long>(SplitMix64(draw_seed) & 0xFFFFFFFFULL);
      r.values = drawn;
      r.values.insert(r.values.end(), cells[g].begin(), cells[g].end());
      runs.push_back(r);
    }
  }
  return runs;
}

int SweepMain(int argc, char** argv) {
  std::string sweep_file, out_dir;
  int jobs = std::max(1u, std::thread::hardware_concurrency()), shard_k = 1, shard_n = 1;
  bool resume = false;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](const std::string& flag) -> std::string {
      if (i + 1 >= argc) throw InputError("", flag, "expects a value");
      return argv[++i];
    };
    if (a == "--out") {
      out_dir = value(a);
    } else if (a == "--jobs") {
      double j;
      if (!IsNumber(value(a), &j) || j < 1 || j > 256 || j != std::floor(j)) {
        throw InputError("", "--jobs", "expected an integer in [1, 256]");
      }
      jobs = static_cast<int>(j);
    } else if (a == "--shard") {
      const std::string s = value(a);
      char rest = 0;
      if (std::sscanf(s.c_str(), "%d/%d%c", &shard_k, &shard_n, &rest) != 2 || shard_n < 1 ||
          shard_k < 1 || shard_k > shard_n) {
        throw InputError("", "--shard", "expected K/N with 1 <= K <= N, got '" + s + "'");
      }
    } else if (a == "--resume") {
      resume = true;
    } else if (a.rfind("--", 0) == 0) {
      throw InputError("", a, "unknown option (see hpa --help)");
    } else if (sweep_file.empty()) {
      sweep_file = a;
    } else {
      throw InputError("", "", "hpa sweep takes one SWEEP.yaml");
    }
  }
  if (sweep_file.empty()) throw InputError("", "", "hpa sweep needs a SWEEP.yaml");
  if (out_dir.empty()) throw InputError("", "--out", "hpa sweep needs --out DIR");

  const SweepSpec spec = LoadSweep(sweep_file);
  const Params params = LoadParams(DefaultParamsPath());
  std::vector<SweepRun> runs = ExpandSweep(spec);
  const size_t total_runs = runs.size();
  runs.erase(std::remove_if(runs.begin(), runs.end(),
                            [&](const SweepRun& r) { return r.index % shard_n != shard_k - 1; }),
             runs.end());
  MakeOutputDir(out_dir);
  const std::string jsonl = out_dir + "/runs.jsonl";
  LockOutputDir(out_dir);
  DropTornLastLine(jsonl);

  // resume: skip what is recorded; refuse to mix sweeps in one folder
  std::set<int> done;
  for (const Record& r : ReadRecords(jsonl)) {
    if (r.sweep_id != spec.sweep_id) {
      throw InputError(
          jsonl, "",
          "holds runs of a different sweep (sweep_id " + r.sweep_id + "); use another --out");
    }
    done.insert(r.run);
  }
  if (!done.empty() && !resume) {
    throw InputError(jsonl, "",
                     "already holds " + std::to_string(done.size()) +
                         " runs; pass --resume to continue or use another --out");
  }
  runs.erase(std::remove_if(runs.begin(), runs.end(),
                            [&](const SweepRun& r) { return done.count(r.index) > 0; }),
             runs.end());
  const std::string tmp_dir = out_dir + "/.running";
  MakeOutputDir(tmp_dir);
  FILE* out = std::fopen(jsonl.c_str(), "a");
  if (!out) throw InputError(jsonl, "", "cannot append to the results file");

  std::printf("sweep %s: %zu runs in all, shard %d/%d: %zu to run (%zu already done), %d jobs\n",
              spec.file.c_str(), total_runs, shard_k, shard_n, runs.size(), done.size(), jobs);
  std::fflush(stdout);
  const bool tty = isatty(STDOUT_FILENO);
  struct Child {
    pid_t pid;
    size_t run;
    Clock::time_point start;
  };
  std::vector<Child> children;
  const pid_t parent_pid = getpid();
  size_t next = 0, finished = 0;
  int failures = 0;
  const auto start = Clock::now();
  auto record = [&](const std::string& line, bool failed, const SweepRun& run) {
    if (std::fprintf(out, "%s\n", line.c_str()) < 0 || std::fflush(out) != 0) {
      throw std::runtime_error("cannot append to " + jsonl + ": " + std::strerror(errno));
    }
    fsync(fileno(out));
    ++finished;
    failures += failed ? 1 : 0;
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    const double eta = elapsed / finished * (runs.size() - finished);
    if (tty) {
      const int width = 30,
                filled = static_cast<int>(width * finished / std::max<size_t>(1, runs.size()));
      std::printf("\r[%s%s] %zu/%zu  failures %d  ETA %.0f s   ", std::string(filled, '#').c_str(),
                  std::string(width - filled, '.').c_str(), finished, runs.size(), failures, eta);
    } else {
      std::printf("run %d done (%zu/%zu, failures %d, ETA %.0f s)\n", run.index, finished,
                  runs.size(), failures, eta);
    }
    std::fflush(stdout);
  };

  while (next < runs.size() || !children.empty()) {
    // start workers up to --jobs
    while (next < runs.size() && static_cast<int>(children.size()) < jobs) {
      const SweepRun& run = runs[next];
      std::fflush(nullptr);
      const pid_t pid = fork();
      if (pid < 0) throw std::runtime_error("fork failed");
      if (pid == 0) {
        // a worker dies with the sweep (kill -9 of the parent included)
        prctl(PR_SET_PDEATHSIG, SIGKILL);
        if (getppid() != parent_pid) _exit(1);
        std::fclose(out);
        const std::string line = RunOne(spec, run, params);
        const std::string path = tmp_dir + "/" + std::to_string(run.index) + ".json";
        std::ofstream(path) << line;
        _exit(0);
      }
      children.push_back({pid, next, Clock::now()});
      ++next;
    }
    // collect finished, crashed or timed-out workers
    bool progressed = false;
    for (size_t c = 0; c < children.size();) {
      int status = 0;
      const SweepRun& run = runs[children[c].run];
      const pid_t r = waitpid(children[c].pid, &status, WNOHANG);
      const double age_s = std::chrono::duration<double>(Clock::now() - children[c].start).count();
      if (r == 0 && age_s > spec.time_limit_s) {
        kill(children[c].pid, SIGKILL);
        waitpid(children[c].pid, &status, 0);
        std::remove((tmp_dir + "/" + std::to_string(run.index) + ".json").c_str());
        record(RecordLine(
                   spec, run, ControllerOf(spec, run),
                   "killed after the time limit of " + FormatNumber(spec.time_limit_s) + " s", ""),
               true, run);
      } else if (r == 0) {
        ++c;
        continue;
      } else {
        const std::string path = tmp_dir + "/" + std::to_string(run.index) + ".json";
        std::ifstream in(path);
        std::string line;
        if (WIFEXITED(status) && WEXITSTATUS(status) == 0 && std::getline(in, line) &&
            !line.empty()) {
          record(line, line.find("\"status\": \"error\"") != std::string::npos, run);
        } else {
          const std::string why =
              WIFSIGNALED(status)
                  ? std::string("worker killed by signal ") + strsignal(WTERMSIG(status))
                  : "worker exited with status " + std::to_string(WEXITSTATUS(status));
          record(RecordLine(spec, run, ControllerOf(spec, run), why, ""), true, run);
        }
        std::remove(path.c_str());
      }
      children.erase(children.begin() + c);
      progressed = true;
    }
    if (!progressed) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::fclose(out);
  rmdir(tmp_dir.c_str());
  if (tty) std::printf("\n");
  const double wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  std::printf(
      "sweep done: %zu runs, %d failures in %.1f s wall (%.1f runs per minute); "
      "results in %s\n",
      finished, failures, wall_s, finished * 60.0 / std::max(wall_s, 1e-9), jsonl.c_str());
  if (shard_n == 1) {
    WriteSummary(ReadRecords(jsonl), out_dir);
    std::printf("summary: %s/summary.md, %s/summary.json, %s/crash_rate.png\n", out_dir.c_str(),
                out_dir.c_str(), out_dir.c_str());
  } else {
    std::printf("shard %d/%d done; join the shards with: hpa merge DIR... --out DIR\n", shard_k,
                shard_n);
  }
  return 0;
}

int MergeMain(int argc, char** argv) {
  std::vector<std::string> dirs;
  std::string out_dir;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out") {
      if (i + 1 >= argc) throw InputError("", "--out", "expects a value");
      out_dir = argv[++i];
    } else if (a.rfind("--", 0) == 0) {
      throw InputError("", a, "unknown option (see hpa --help)");
    } else {
      dirs.push_back(a);
    }
  }
  if (dirs.empty()) throw InputError("", "", "hpa merge needs at least one sweep DIR");
  if (out_dir.empty()) throw InputError("", "--out", "hpa merge needs --out DIR");
  std::map<int, Record> by_run;
  std::string sweep_id;
  for (const std::string& d : dirs) {
    const std::string path = d + "/runs.jsonl";
    struct stat st;
    if (stat(path.c_str(), &st) != 0) throw InputError(path, "", "no runs.jsonl in this folder");
    if (!S_ISREG(st.st_mode) || access(path.c_str(), R_OK) != 0) {
      throw InputError(path, "", "not a readable file");
    }
    for (Record& r : ReadRecords(path)) {
      if (sweep_id.empty()) sweep_id = r.sweep_id;
      if (r.sweep_id != sweep_id) {
        throw InputError(path, "sweep_id",
                         "mixes sweeps (" + r.sweep_id + " vs " + sweep_id +
                             "); merge only shards of one sweep");
      }
      by_run[r.run] = r;  // a run recorded twice (resume after a torn write) counts once
    }
  }
  MakeOutputDir(out_dir);
  std::vector<Record> records;
  {
    std::ofstream merged(out_dir + "/runs.jsonl.tmp");
    for (auto& [index, r] : by_run) {
      merged << r.line << "\n";
      records.push_back(r);
    }
  }
  std::rename((out_dir + "/runs.jsonl.tmp").c_str(), (out_dir + "/runs.jsonl").c_str());
  WriteSummary(records, out_dir);
  std::printf(
      "merged %zu runs from %zu folders into %s (summary.md, summary.json, crash_rate.png)\n",
      records.size(), dirs.size(), out_dir.c_str());
  return 0;
}

}  // namespace hpa
