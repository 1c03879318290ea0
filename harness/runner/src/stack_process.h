#pragma once
// One separate flight stack's process and socket (private to the runner), as a single vehicle's
// stack and each of a team's stacks use it: the simulator serves a Unix socket in a directory of
// its own, starts the command in a process group of its own with HPA_FLIGHT_SOCKET set
// (flight_process.h), waits for it to connect, bounds each message's wait (a stop signal ends it
// after a short grace), turns a failed protocol step into a run error naming the stack, the step
// and how the process ended, and at the end stops the process and removes the socket.

#include <sys/types.h>

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "hpa/flight/protocol.h"

namespace hpa::runner {

/// How long a stack may take to connect (s).
inline constexpr double kConnectTimeoutS = 30.0;

/// One separate stack's process, its socket and whether it failed.
class StackProcess {
 public:
  /// The clock of the deadlines.
  using Clock = std::chrono::steady_clock;

  /// `who`: the stack as error messages name it ("flight stack 'CMD'", with its vehicle for a
  /// team's); `step_timeout_s`: the longest wait for one whole message.
  StackProcess(std::string who, double step_timeout_s);
  /// Cleanup.
  ~StackProcess();
  StackProcess(const StackProcess&) = delete;
  StackProcess& operator=(const StackProcess&) = delete;

  /// The time `seconds` from now.
  static Clock::time_point After(double seconds);

  /// Serves a socket in a new directory of its own and starts `command` with /bin/sh in a process
  /// group of its own, with HPA_FLIGHT_SOCKET and each of `env` (name, value) set; throws
  /// flight::ProtocolError naming the stack when it cannot.
  void Start(const std::string& command,
             const std::vector<std::pair<std::string, std::string>>& env = {});

  /// Waits for the stack to connect until `deadline`, polling for its end and for a stop signal;
  /// throws flight::ProtocolError naming the stack (and `timeout_s`, the wait it was given) when
  /// it ends or does not connect, flight::WaitInterrupted when a stop ends the wait.
  void Accept(Clock::time_point deadline, double timeout_s);

  /// The connection (after Accept).
  flight::Channel& channel() { return *channel_; }

  /// One message's wait: the step timeout, ended a short grace after a stop was requested.
  flight::WaitLimit Limit();

  /// Whether the stack may be asked again (at the finish): it has not failed, and a stop, if one
  /// was requested, is still within its grace.
  bool Finishable() { return !failed_ && !StopDue(); }

  /// Runs the protocol step `f`; a protocol failure is rethrown naming the stack, the step and,
  /// if the process has ended, how; a wait a stop signal ended is rethrown as the stop
  /// (flight::WaitInterrupted). A stack that failed before is not asked again.
  template <class F>
  void Guard(F&& f, const std::string& step) {
    if (failed_) Fail(step + ": not sent, the flight stack failed before");
    try {
      f();
    } catch (const flight::WaitInterrupted&) {
      Stopped("(" + step + ")");
    } catch (const flight::ProtocolError& e) {
      Failed(step, e);
    }
  }

  /// Throws flight::ProtocolError naming the stack and `what`.
  [[noreturn]] void Fail(const std::string& what) const;

  /// Closes the socket (a stack waiting on it sees the end), stops the process (its group and
  /// every process carrying its socket) and removes the socket's directory.
  void Cleanup();

 private:
  // Whether a stop was requested the grace ago or more (from when a wait first saw it).
  bool StopDue();
  // Ends the run as stopped by the requested signal while it waited on the stack (`during` says
  // for what); the stack is killed and not asked again.
  [[noreturn]] void Stopped(const std::string& during);
  // Rethrows `e`, the failure of `step`, naming the stack, the step and how the process ended.
  [[noreturn]] void Failed(const std::string& step, const flight::ProtocolError& e);
  void Listen();
  // Waits up to wait_s (cut short by a stop signal) for the process to end and notes how it
  // ended; if it has not and `stop` is set, kills its process group.
  void Reap(double wait_s, bool stop);
  void KillGroup() const;

  std::string who_;        // the stack as error messages name it
  double step_timeout_s_;  // the longest wait for one message
  std::string dir_, socket_path_, exit_note_;
  int listen_fd_ = -1;
  pid_t pid_ = 0, pgid_ = 0;
  std::unique_ptr<flight::Channel> channel_;
  bool failed_ = false;                        // a message failed: the stack is not asked again
  std::optional<Clock::time_point> stop_due_;  // waits end then (a stop)
};

}  // namespace hpa::runner
