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
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "hpa/models/input_error.h"
#include "hpa/scenarios/metrics.h"
#include "hpa/scenarios/runner.h"
#include "harness/runner/src/flight_process.h"
#include "harness/sweeps/src/sweep_internal.h"

namespace hpa::sweep {
namespace {

using Clock = std::chrono::steady_clock;
// A worker's exit status when it could not write a run's record: the sweep stops (exit 4).
constexpr int kWorkerCannotWrite = 74;
// What the pool calls with each finished run's JSON line, whether it failed, and the run.
using RecordFn = std::function<void(const std::string& line, bool failed, const SweepRun&)>;

// What flew a run whose process died: its controller type, or "external" for a flight stack
// (its name is known only from its hello, which the dead worker did not pass on).
std::string ControllerOf(const SweepSpec& spec, const SweepRun& run) {
  if (!FlightStackOf(spec, run).empty()) return "external";
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
  const std::string flight_stack = FlightStackOf(spec, run);
  std::string controller = flight_stack.empty() ? "?" : "external";
  try {
    const Scenario scenario = BuildScenario(spec, run);
    if (flight_stack.empty()) controller = scenario.controller.type;
    RunOptions options;
    options.gl_backend = gl_backend;
    options.flight_stack = flight_stack;
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

// One forked worker process: it flies the runs it is handed down one pipe, one at a time, and
// says each is done on the other (its record is in the run's file by then).
class Worker {
 public:
  // Forks a worker that calls `fly(position)` for each position it is handed, until its pipe
  // closes. `siblings` are the other workers: their pipe ends are not this one's and are closed
  // in the child (they close when those workers die).
  Worker(const std::function<void(uint64_t)>& fly, const std::vector<Worker>& siblings,
         pid_t parent_pid) {
    int down[2], up[2];
    if (pipe(down) != 0) throw std::runtime_error("pipe failed");
    if (pipe(up) != 0) {
      close(down[0]);
      close(down[1]);
      throw std::runtime_error("pipe failed");
    }
    std::fflush(nullptr);
    pid_ = fork();
    if (pid_ < 0) throw std::runtime_error("fork failed");
    if (pid_ == 0) {
      // a worker dies with the sweep (kill -9 of the parent included)
      prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (getppid() != parent_pid) _exit(1);
      for (const Worker& other : siblings) {
        close(other.to_worker_);
        close(other.from_worker_);
      }
      close(down[1]);
      close(up[0]);
      uint64_t position = 0;
      while (ReadFully(down[0], &position, sizeof position)) {
        fly(position);
        if (!WriteFully(up[1], &position, sizeof position)) _exit(1);
      }
      _exit(0);
    }
    close(down[0]);
    close(up[1]);
    to_worker_ = down[1];
    from_worker_ = up[0];
  }

  // Hands it the run at `position`; false when it died (reaped by the caller's next poll).
  bool Hand(size_t position) {
    const uint64_t p = position;
    if (!WriteFully(to_worker_, &p, sizeof p)) return false;
    run_ = position;
    start_ = Clock::now();
    return true;
  }

  // What its pipe said after a poll: the run it flies is done, it died, or nothing yet.
  enum class Answer { kNone, kDone, kDied };
  Answer Read(short revents) {
    uint64_t done = 0;
    if ((revents & POLLIN) != 0 && ReadFully(from_worker_, &done, sizeof done) && run_ &&
        done == *run_) {
      return Answer::kDone;
    }
    return (revents & (POLLIN | POLLHUP | POLLERR)) != 0 ? Answer::kDied : Answer::kNone;
  }

  // Closes its pipes and reaps it (killed first when `kill_it`); its wait status.
  int End(bool kill_it) {
    if (kill_it) kill(pid_, SIGKILL);
    close(to_worker_);
    close(from_worker_);
    int status = 0;
    while (waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    return status;
  }

  // Seconds since it was handed its run.
  double RunSeconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

  // The position of the run it flies, if any.
  const std::optional<size_t>& run() const { return run_; }
  // It has no run: the next round hands it one or ends it.
  void SetIdle() { run_.reset(); }
  // The end of the pipe it answers on.
  int answer_fd() const { return from_worker_; }

 private:
  pid_t pid_ = -1;
  int to_worker_ = -1, from_worker_ = -1;  // the parent's ends
  std::optional<size_t> run_;              // position of the run it flies
  Clock::time_point start_;                // when that run was handed to it
};

// Why a worker's process ended, from its wait status.
std::string EndedBecause(int status) {
  return WIFSIGNALED(status) ? std::string("worker killed by signal ") + strsignal(WTERMSIG(status))
                             : "worker exited with status " + std::to_string(WEXITSTATUS(status));
}

// The pool: hands runs to idle workers, starts workers up to `jobs`, and turns each worker's
// answer (done, died, past the time limit) into the run's record.
class Pool {
 public:
  Pool(const SweepSpec& spec, const std::vector<SweepRun>& runs, const Params& params,
       sim::GlBackend gl_backend, int jobs, const std::string& tmp_dir, const RecordFn& record)
      : spec_(spec), runs_(runs), jobs_(jobs), tmp_dir_(tmp_dir), record_(record) {
    fly_ = [this, &params, gl_backend](uint64_t position) {
      const std::string line = RunOne(spec_, runs_[position], params, gl_backend);
      std::ofstream out(PathOf(position));
      out << line;
      out.flush();
      if (!out) {
        // a record cut short (a full disk, the file-size limit) is none: the worker ends with
        // the code that stops the sweep (Collect), never passing a torn record on
        out.close();
        std::remove(PathOf(position).c_str());
        _exit(kWorkerCannotWrite);
      }
    };
  }

  // Runs every run; 0, or the signal of a stop request.
  int Run() {
    const IgnoreSigpipe ignore_sigpipe;
    while (next_ < runs_.size() || !workers_.empty()) {
      if (StopRequested() != 0) return Stop();
      HandOut();
      if (next_ >= runs_.size() && workers_.empty()) break;
      const std::vector<pollfd> fds = Wait();
      if (StopRequested() != 0) return Stop();
      Collect(fds);
    }
    return 0;
  }

 private:
  // Each idle worker gets the next run, or ends when none is left (two workers that finish in
  // one round may both be idle with one run left); workers are started up to --jobs while runs
  // remain.
  void HandOut() {
    for (size_t i = 0; i < workers_.size();) {
      Worker& w = workers_[i];
      if (!w.run() && next_ >= runs_.size()) {
        w.End(false);  // its pipe closes and it exits
        workers_.erase(workers_.begin() + static_cast<long>(i));
        continue;
      }
      if (!w.run() && w.Hand(next_)) ++next_;
      ++i;
    }
    while (next_ < runs_.size() && static_cast<int>(workers_.size()) < jobs_) {
      const std::vector<Worker> siblings = workers_;
      workers_.emplace_back(fly_, siblings, parent_pid_);
      if (!workers_.back().Hand(next_)) break;  // it died: reaped by Collect
      ++next_;
    }
  }

  // Waits at most 20 ms for a worker to answer (or die): stops and time limits are checked.
  std::vector<pollfd> Wait() const {
    std::vector<pollfd> fds;
    for (const Worker& w : workers_) fds.push_back({w.answer_fd(), POLLIN, 0});
    if (poll(fds.data(), fds.size(), 20) < 0 && errno != EINTR) {
      throw std::runtime_error(std::string("poll failed: ") + std::strerror(errno));
    }
    return fds;
  }

  // Records what each worker's answer says; a worker that died or ran past the time limit is
  // reaped, its flight stack reclaimed, and its run recorded as failed.
  void Collect(const std::vector<pollfd>& fds) {
    std::vector<Worker> alive;
    for (size_t i = 0; i < workers_.size(); ++i) {
      Worker& w = workers_[i];
      const Worker::Answer answer = w.Read(fds[i].revents);
      if (answer == Worker::Answer::kDone) {
        RecordFinished(*w.run());
        w.SetIdle();
      } else if (answer == Worker::Answer::kDied) {
        const int status = w.End(true);
        if (WIFEXITED(status) && WEXITSTATUS(status) == kWorkerCannotWrite) {
          throw OutputError(tmp_dir_, "a worker could not write the record of run " +
                                          std::to_string(runs_[*w.run()].index) +
                                          " (the disk is full or the file-size limit reached)");
        }
        if (w.run()) RecordLost(*w.run(), EndedBecause(status));
        ReclaimStack();
        continue;
      } else if (w.run() && w.RunSeconds() > spec_.time_limit_s) {
        w.End(true);
        RecordLost(*w.run(),
                   "killed after the time limit of " + FormatNumber(spec_.time_limit_s) + " s");
        ReclaimStack();
        continue;
      }
      alive.push_back(w);
    }
    workers_ = std::move(alive);
  }

  // The record a worker wrote for the run at `position` (a failure when it wrote none).
  void RecordFinished(size_t position) {
    std::ifstream in(PathOf(position));
    std::string line;
    const SweepRun& run = runs_[position];
    if (std::getline(in, line) && !line.empty()) {
      record_(line, RecordFailed(line), run);
    } else {
      RecordLost(position, "worker wrote no record");
    }
    std::remove(PathOf(position).c_str());
  }

  // A failed record for the run at `position`, which its worker did not finish.
  void RecordLost(size_t position, const std::string& why) {
    const SweepRun& run = runs_[position];
    std::remove(PathOf(position).c_str());
    record_(RecordLine(spec_, run, ControllerOf(spec_, run), why, ""), true, run);
  }

  // A stop: the workers die with their runs unrecorded (resume runs them again).
  int Stop() {
    for (Worker& w : workers_) {
      w.End(true);
      if (w.run()) std::remove(PathOf(*w.run()).c_str());
    }
    workers_.clear();
    ReclaimStack();
    return StopRequested();
  }

  // A worker killed in a run leaves its flight stack's processes, socket folder and frame ring
  // (it could not clean up): reclaimed as soon as it is reaped, not at the next stack's start.
  void ReclaimStack() const {
    if (!spec_.flight_stack.empty() || !spec_.flight_stacks.empty()) {
      runner::RemoveStaleFlightRuns();
    }
  }

  // The file a worker writes the record of the run at `position` into.
  std::string PathOf(size_t position) const {
    return tmp_dir_ + "/" + std::to_string(runs_[position].index) + ".json";
  }

  const SweepSpec& spec_;
  const std::vector<SweepRun>& runs_;
  const int jobs_;
  const std::string tmp_dir_;
  const RecordFn& record_;
  const pid_t parent_pid_ = getpid();
  std::function<void(uint64_t)> fly_;  // what a worker does with a run (in the child)
  std::vector<Worker> workers_;
  size_t next_ = 0;  // position of the next run to hand out
};

}  // namespace

int RunPool(const SweepSpec& spec, const std::vector<SweepRun>& runs, const Params& params,
            sim::GlBackend gl_backend, int jobs, const std::string& tmp_dir,
            const RecordFn& record) {
  return Pool(spec, runs, params, gl_backend, jobs, tmp_dir, record).Run();
}

}  // namespace hpa::sweep
