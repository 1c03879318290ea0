// Sweep results I/O: runs.jsonl records (nlohmann-json), the output-folder lock, repairs.

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "hpa/models/file_io.h"
#include "hpa/models/input_error.h"
#include "hpa/scenarios/metric_defs.h"
#include "hpa/scenarios/provenance.h"
#include "harness/cli/src/cli_parse.h"
#include "harness/sweeps/src/sweep_internal.h"

namespace hpa::sweep {

using Json = nlohmann::ordered_json;

// Two sweeps writing one runs.jsonl would record every run twice: the lock is held (the file
// descriptor kept open) until the process exits.
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

int DropErrorRecords(const std::string& jsonl) {
  std::ifstream in(jsonl);
  if (!in) return 0;
  std::string kept, line;
  int dropped = 0;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    bool error = false;
    try {
      error = Json::parse(line).at("status").get<std::string>() != "ok";
    } catch (const Json::exception&) {
      error = true;  // an unreadable record is no result either
    }
    if (error) {
      ++dropped;
    } else {
      kept += line + "\n";
    }
  }
  if (dropped == 0) return 0;
  // replaced in one rename: a kill during the rewrite leaves the old file whole
  WriteFileAtomic(jsonl, kept);
  return dropped;
}

std::vector<Record> UniqueRecords(const std::vector<Record>& records, long expected_runs,
                                  std::vector<std::string>* warnings) {
  // the metrics without the fields that measure the machine: two runs of one draw agree there
  const auto outcome = [](const Record& r) {
    Json j = Json::parse(r.line, nullptr, false);
    if (j.is_discarded()) return r.line;
    if (j.contains("metrics") && j["metrics"].is_object()) {
      for (const char* key :
           {"wall_time_s", "mpc_solve_ms", "render_ms", "detector_ms", "image_model_ms"}) {
        j["metrics"].erase(key);
      }
    }
    return j.dump();
  };
  std::map<int, Record> by_run;
  for (const Record& r : records) {
    if (r.run < 0 || (expected_runs >= 0 && r.run >= expected_runs)) {
      warnings->push_back("run " + std::to_string(r.run) + " is outside the sweep's runs 0.." +
                          std::to_string(expected_runs - 1) + ": left out");
      continue;
    }
    const auto [it, inserted] = by_run.emplace(r.run, r);
    if (inserted) continue;
    Record& kept = it->second;
    if (kept.error && !r.error) {
      kept = r;  // a retried run that finished
    } else if (!kept.error && !r.error && outcome(kept) != outcome(r)) {
      warnings->push_back("run " + std::to_string(r.run) +
                          " is recorded twice with different results: the first is kept");
    }
  }
  std::vector<Record> out;
  for (auto& [index, r] : by_run) out.push_back(std::move(r));
  return out;
}

std::vector<Record> ReadRecords(const std::string& path) {
  std::vector<Record> out;
  if (access(path.c_str(), F_OK) == 0) CheckInputFile(path, "a sweep's runs.jsonl");
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
      if (n.contains("flight_stack")) r.flight_stack = n.at("flight_stack").get<std::string>();
      r.error = n.at("status").get<std::string>() != "ok";
      if (r.error) {
        // a run error fails the run's verdict; its first cause says how ("never flew: ...")
        r.expect_failed = true;
        r.error_text = n.at("error").is_string() ? n.at("error").get<std::string>() : "";
        const Json m = n.contains("metrics") ? n["metrics"] : Json();
        const Json* failed = m.is_object() && m.contains("expect") && m["expect"].is_object() &&
                                     m["expect"].contains("failed")
                                 ? &m["expect"]["failed"]
                                 : nullptr;
        if (failed && failed->is_array() && !failed->empty() && (*failed)[0].is_string()) {
          r.error_text = (*failed)[0].get<std::string>();
        }
      } else {
        const Json& m = n.at("metrics");
        r.crashed = m.at("crashed").get<bool>();
        r.expect_failed = !m.at("expect").at("passed").get<bool>();
        // metrics by the metric table's names; NaN where the run did not measure one
        const auto metric = [&m](const char* name) {
          return ReadMetric(name, m).value_or(std::nan(""));
        };
        r.payload_rmse_norm_m = metric("payload_rmse_norm_m");
        r.quad_dev_max_m = metric("quad_position_deviation_max_m");
        r.solve_median_ms = metric("mpc_solve_median_ms");
        r.slack_time_s = metric("slack_time_s");
        r.payload_in_fov = metric("payload_in_fov_fraction");
        r.mode_accuracy = metric("mode_accuracy");
        if (m.contains("estimator") && m["estimator"].is_object()) {
          const Json& e = m["estimator"];
          for (const char* key : {"resets", "cable_reinitialisations"}) {
            if (e.contains(key) && e[key].is_number()) r.estimator_restarts += e[key].get<double>();
          }
        }
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

std::string RecordLine(const SweepSpec& spec, const SweepRun& run, const std::string& controller,
                       const std::string& error, const std::string& metrics_json) {
  Json line;
  line["sweep_id"] = spec.sweep_id;
  if (!spec.inputs_id.empty()) line["inputs_id"] = spec.inputs_id;
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
  const std::string flight_stack = FlightStackOf(spec, run);
  if (!flight_stack.empty()) line["flight_stack"] = flight_stack;
  line["status"] = error.empty() ? "ok" : "error";
  line["error"] = error.empty() ? Json() : Json(error);
  line["metrics"] = metrics_json.empty() ? Json() : Json::parse(metrics_json);
  // the build once per line, also for a run that ended in an error (no metrics)
  if (line["metrics"].is_object()) line["metrics"].erase("build");
  line["build"] = BuildToJson(ThisBuild());
  // one line, invalid UTF-8 in names or messages replaced rather than thrown on
  return line.dump(-1, ' ', false, Json::error_handler_t::replace);
}

}  // namespace hpa::sweep
