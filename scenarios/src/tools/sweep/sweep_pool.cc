// The sweep's worker pool: up to --jobs forked worker processes, each flying the runs it is
// handed one at a time (a crash or a hang costs one run and that worker, which is replaced, not
// the sweep), a time limit per run, workers that die with the sweep.

#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "hpa/scenarios/metrics.h"
#include "hpa/scenarios/runner.h"
#include "scenarios/src/runner/flight_process.h"
#include "scenarios/src/tools/sweep/sweep_internal.h"

namespace hpa::sweep {
namespace {

using Clock = std::chrono::steady_clock;

// What flew a run whose process died: its controller type, or "external" for a flight stack
// (its name is known only from its hello, which the dead worker did not pass on).
std::string ControllerOf(const SweepSpec& spec, const SweepRun& run) {
  if (!spec.flight_stack.empty()) return "external";
  try {
    return BuildScenario(spec, run).controller.type;
  } catch (const std::exception&) {
    return "?";
  }
}

// Runs one sweep run in this (child) process and returns its JSON line. A flight stack is
// started for this run alone (its socket folder and frame ring carry this worker's pid, so
// parallel workers' never meet); its failure is this run's run error.
std::string RunOne(const SweepSpec& spec, const SweepRun& run, const Params& params,
                   sim::GlBackend gl_backend) {
  std::string controller = spec.flight_stack.empty() ? "?" : "external";
  try {
    const Scenario scenario = BuildScenario(spec, run);
    if (spec.flight_stack.empty()) controller = scenario.controller.type;
    RunOptions options;
    options.gl_backend = gl_backend;
    options.flight_stack = spec.flight_stack;
    options.flight_step_timeout_s = spec.flight_timeout_s;
    const RunResult result = RunScenario(scenario, params, options);
    const std::string metrics = MetricsToJson(result.metrics);
    // labelled by what flew: the controller type, or the name the stack gave in its hello
    return RecordLine(spec, run, result.metrics.controller, result.metrics.run_error.value_or(""),
                      metrics);
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

namespace {

// Moves exactly n bytes between fd and p with `transfer` (read or write), again after a
// signal; false at the end of the file or on an error.
template <typename Byte, typename Transfer>
bool TransferFully(int fd, Byte* p, size_t n, Transfer transfer) {
  while (n > 0) {
    const ssize_t done = transfer(fd, p, n);
    if (done < 0 && errno == EINTR) continue;
    if (done <= 0) return false;
    p += done;
    n -= static_cast<size_t>(done);
  }
  return true;
}

// Reads exactly n bytes (false: end of file or an error).
bool ReadFully(int fd, void* data, size_t n) {
  return TransferFully(fd, static_cast<char*>(data), n, ::read);
}

// Writes exactly n bytes (false: an error, e.g. the reader is gone).
bool WriteFully(int fd, const void* data, size_t n) {
  return TransferFully(fd, static_cast<const char*>(data), n, ::write);
}

// Ignores SIGPIPE while it lives: a worker that died makes the write of its next run fail
// instead of killing the sweep.
class IgnoreSigpipe {
 public:
  IgnoreSigpipe() : previous_(signal(SIGPIPE, SIG_IGN)) {}
  ~IgnoreSigpipe() { signal(SIGPIPE, previous_); }
  IgnoreSigpipe(const IgnoreSigpipe&) = delete;
  IgnoreSigpipe& operator=(const IgnoreSigpipe&) = delete;

 private:
  void (*previous_)(int);
};

// One worker process: the pipe its runs go down, the pipe it says "done" on, and its run.
struct Worker {
  pid_t pid = -1;
  int to_worker = -1, from_worker = -1;  // the parent's ends
  std::optional<size_t> run;             // position in `runs` of the run it flies
  Clock::time_point start;               // when that run was handed to it
};

}  // namespace

int RunPool(
    const SweepSpec& spec, const std::vector<SweepRun>& runs, const Params& params,
    sim::GlBackend gl_backend, int jobs, const std::string& tmp_dir,
    const std::function<void(const std::string& line, bool failed, const SweepRun&)>& record) {
  const pid_t parent_pid = getpid();
  const IgnoreSigpipe ignore_sigpipe;
  size_t next = 0;
  std::vector<Worker> workers;
  // ends a worker: closes its pipes and reaps it (killed first when `kill_it`); its status
  const auto end_worker = [&](Worker& w, bool kill_it) {
    if (kill_it) kill(w.pid, SIGKILL);
    close(w.to_worker);
    close(w.from_worker);
    int status = 0;
    while (waitpid(w.pid, &status, 0) < 0 && errno == EINTR) {
    }
    return status;
  };
  // a worker killed in a run leaves its flight stack's processes, socket folder and frame ring
  // (it could not clean up); reclaimed as soon as it is reaped, not at the next stack's start
  const auto reclaim_stack = [&]() {
    if (!spec.flight_stack.empty()) runner::RemoveStaleFlightRuns();
  };
  const auto path_of = [&](size_t position) {
    return tmp_dir + "/" + std::to_string(runs[position].index) + ".json";
  };
  // a stop: the workers die with their runs unrecorded (resume runs them again)
  const auto stop = [&]() {
    for (Worker& w : workers) {
      end_worker(w, true);
      if (w.run) std::remove(path_of(*w.run).c_str());
    }
    workers.clear();
    reclaim_stack();
    return StopRequested();
  };
  // a worker forked from this process: it flies the runs it is handed, one at a time, until
  // its pipe closes
  const auto start_worker = [&]() {
    int down[2], up[2];
    if (pipe(down) != 0) throw std::runtime_error("pipe failed");
    if (pipe(up) != 0) {
      close(down[0]);
      close(down[1]);
      throw std::runtime_error("pipe failed");
    }
    std::fflush(nullptr);
    const pid_t pid = fork();
    if (pid < 0) throw std::runtime_error("fork failed");
    if (pid == 0) {
      // a worker dies with the sweep (kill -9 of the parent included)
      prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (getppid() != parent_pid) _exit(1);
      // the other workers' pipes are not this one's: their ends close when they die
      for (const Worker& other : workers) {
        close(other.to_worker);
        close(other.from_worker);
      }
      close(down[1]);
      close(up[0]);
      uint64_t position = 0;
      while (ReadFully(down[0], &position, sizeof position)) {
        const SweepRun& run = runs[position];
        const std::string line = RunOne(spec, run, params, gl_backend);
        {
          std::ofstream out(path_of(position));
          out << line;
        }
        if (!WriteFully(up[1], &position, sizeof position)) _exit(1);
      }
      _exit(0);
    }
    close(down[0]);
    close(up[1]);
    Worker w;
    w.pid = pid;
    w.to_worker = down[1];
    w.from_worker = up[0];
    workers.push_back(w);
  };

  while (next < runs.size() || !workers.empty()) {
    if (StopRequested() != 0) return stop();
    // every idle worker gets the next run, or ends when none is left (two workers that finish
    // in one round may both be idle with one run left); workers are started up to --jobs while
    // runs remain
    for (size_t i = 0; i < workers.size();) {
      Worker& w = workers[i];
      if (!w.run && next >= runs.size()) {
        end_worker(w, false);  // its pipe closes and it exits
        workers.erase(workers.begin() + static_cast<long>(i));
        continue;
      }
      if (!w.run) {
        const uint64_t position = next;
        if (WriteFully(w.to_worker, &position, sizeof position)) {
          w.run = next++;
          w.start = Clock::now();
        }
      }
      ++i;
    }
    if (next >= runs.size() && workers.empty()) break;
    while (next < runs.size() && static_cast<int>(workers.size()) < jobs) {
      start_worker();
      Worker& w = workers.back();
      const uint64_t position = next;
      if (!WriteFully(w.to_worker, &position, sizeof position)) break;  // it died: reaped below
      w.run = next++;
      w.start = Clock::now();
    }
    // wait for a worker to answer (or die), at most 20 ms: stops and time limits are checked
    std::vector<pollfd> fds;
    for (const Worker& w : workers) fds.push_back({w.from_worker, POLLIN, 0});
    if (poll(fds.data(), fds.size(), 20) < 0 && errno != EINTR) {
      throw std::runtime_error(std::string("poll failed: ") + std::strerror(errno));
    }
    if (StopRequested() != 0) return stop();
    for (size_t i = 0; i < workers.size();) {
      Worker& w = workers[i];
      const short revents = fds[i].revents;
      uint64_t done = 0;
      if ((revents & POLLIN) != 0 && ReadFully(w.from_worker, &done, sizeof done) && w.run &&
          done == *w.run) {
        // its run finished: the record it wrote
        std::ifstream in(path_of(*w.run));
        std::string line;
        const SweepRun& run = runs[*w.run];
        if (std::getline(in, line) && !line.empty()) {
          record(line, RecordFailed(line), run);
        } else {
          record(RecordLine(spec, run, ControllerOf(spec, run), "worker wrote no record", ""), true,
                 run);
        }
        std::remove(path_of(*w.run).c_str());
        w.run.reset();  // idle: the next round hands it a run or ends it
        ++i;
        continue;
      }
      if ((revents & (POLLIN | POLLHUP | POLLERR)) != 0) {
        // it died (end of file on its pipe), with its run unfinished
        const int status = end_worker(w, true);
        reclaim_stack();
        if (w.run) {
          const SweepRun& run = runs[*w.run];
          const std::string why =
              WIFSIGNALED(status)
                  ? std::string("worker killed by signal ") + strsignal(WTERMSIG(status))
                  : "worker exited with status " + std::to_string(WEXITSTATUS(status));
          record(RecordLine(spec, run, ControllerOf(spec, run), why, ""), true, run);
          std::remove(path_of(*w.run).c_str());
        }
        workers.erase(workers.begin() + static_cast<long>(i));
        fds.erase(fds.begin() + static_cast<long>(i));
        continue;
      }
      if (w.run &&
          std::chrono::duration<double>(Clock::now() - w.start).count() > spec.time_limit_s) {
        end_worker(w, true);
        reclaim_stack();
        const SweepRun& run = runs[*w.run];
        std::remove(path_of(*w.run).c_str());
        record(RecordLine(
                   spec, run, ControllerOf(spec, run),
                   "killed after the time limit of " + FormatNumber(spec.time_limit_s) + " s", ""),
               true, run);
        workers.erase(workers.begin() + static_cast<long>(i));
        fds.erase(fds.begin() + static_cast<long>(i));
        continue;
      }
      ++i;
    }
  }
  return 0;
}

}  // namespace hpa::sweep
