// The sweep's worker pool: each run in a forked process (a crash or a hang costs one run, not
// the sweep), up to --jobs at once, a time limit per run, workers that die with the sweep.

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "hpa/scenarios/metrics.h"
#include "hpa/scenarios/runner.h"
#include "scenarios/src/tools/sweep/sweep_internal.h"

namespace hpa::sweep {
namespace {

using Clock = std::chrono::steady_clock;

// The controller type of a run (for records of runs whose process died).
std::string ControllerOf(const SweepSpec& spec, const SweepRun& run) {
  try {
    return BuildScenario(spec, run).controller.type;
  } catch (const std::exception&) {
    return "?";
  }
}

// Runs one sweep run in this (child) process and returns its JSON line.
std::string RunOne(const SweepSpec& spec, const SweepRun& run, const Params& params,
                   sim::GlBackend gl_backend) {
  std::string controller = "?";
  try {
    const Scenario scenario = BuildScenario(spec, run);
    controller = scenario.controller.type;
    RunOptions options;
    options.gl_backend = gl_backend;
    const RunResult result = RunScenario(scenario, params, options);
    const std::string metrics = MetricsToJson(result.metrics);
    return RecordLine(spec, run, controller, result.metrics.run_error.value_or(""), metrics);
  } catch (const std::exception& e) {
    return RecordLine(spec, run, controller, e.what(), "");
  }
}

// True if a worker's JSON line records an error (or cannot be read).
bool RecordFailed(const std::string& line) {
  try {
    return nlohmann::json::parse(line).at("status").get<std::string>() != "ok";
  } catch (const nlohmann::json::exception&) {
    return true;
  }
}

}  // namespace

int RunPool(
    const SweepSpec& spec, const std::vector<SweepRun>& runs, const Params& params,
    sim::GlBackend gl_backend, int jobs, const std::string& tmp_dir,
    const std::function<void(const std::string& line, bool failed, const SweepRun&)>& record) {
  const pid_t parent_pid = getpid();
  size_t next = 0;
  struct Child {
    pid_t pid;
    size_t run;
    Clock::time_point start;
  };
  std::vector<Child> children;
  // a stop: the workers die with their runs unrecorded (resume runs them again)
  const auto stop = [&]() {
    for (const Child& child : children) kill(child.pid, SIGKILL);
    for (const Child& child : children) {
      int status = 0;
      waitpid(child.pid, &status, 0);
      std::remove((tmp_dir + "/" + std::to_string(runs[child.run].index) + ".json").c_str());
    }
    children.clear();
    return StopRequested();
  };
  while (next < runs.size() || !children.empty()) {
    if (StopRequested() != 0) return stop();
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
        const std::string line = RunOne(spec, run, params, gl_backend);
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
      if (StopRequested() != 0) return stop();
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
          record(line, RecordFailed(line), run);
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
  return 0;
}

}  // namespace hpa::sweep
