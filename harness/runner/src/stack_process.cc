#include "harness/runner/src/stack_process.h"

#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <thread>

#include "hpa/scenarios/runner.h"
#include "harness/runner/src/flight_process.h"

namespace hpa::runner {
namespace {

using flight::ProtocolError;

// How long the waits on a stack go on once a stop was requested (s): a stack that answers
// promptly completes the message in flight and its finish report, a hung one is abandoned.
constexpr double kStopGraceS = 0.2;

// How long a stack that broke the protocol is given to end (s), so the run error can say how it
// ended; the wait ends as soon as it has, and one still running after it is killed.
constexpr double kExitNoteWaitS = 2.0;

// How long a stack whose socket closed at the run's end is given to exit (s) before it is killed.
constexpr double kExitWaitS = 2.0;

// The directory of the running executable (hpa-flight sits beside hpa).
std::string ExecutableDir() {
  char buf[PATH_MAX];
  const ssize_t n = ::readlink("/proc/self/exe", buf, sizeof buf - 1);
  if (n <= 0) return "";
  std::string path(buf, static_cast<size_t>(n));
  return path.substr(0, path.rfind('/'));
}

// Whether a stop (SIGINT, SIGTERM) was requested.
bool Stopping() { return StopRequested() != 0; }

// `value` as one word of /bin/sh (quoted unless it needs no quoting).
std::string ShellWord(const std::string& value) {
  const bool plain = !value.empty() && value.find_first_not_of(
                                           "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                           "0123456789_./-") == std::string::npos;
  if (plain) return value;
  std::string out = "'";
  for (const char c : value) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

StackProcess::StackProcess(std::string who, double step_timeout_s)
    : who_(std::move(who)), step_timeout_s_(step_timeout_s) {}

StackProcess::~StackProcess() { Cleanup(); }

StackProcess::Clock::time_point StackProcess::After(double seconds) {
  return Clock::now() +
         std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

void StackProcess::Start(const std::string& command,
                         const std::vector<std::pair<std::string, std::string>>& env) {
  std::string dir = "/tmp/hpa-flight-" + FlightOwnerTag() + "-XXXXXX";
  if (::mkdtemp(dir.data()) == nullptr) Fail(std::string("mkdtemp: ") + std::strerror(errno));
  dir_ = dir;
  socket_path_ = dir_ + "/lockstep.sock";
  Listen();
  // the extra variables, exported by the shell before the command
  std::string line;
  for (const auto& [name, value] : env) {
    line += name + "=" + ShellWord(value) + "; export " + name + "; ";
  }
  line += command;
  const std::string path_env =
      ExecutableDir() + ":" + (std::getenv("PATH") ? std::getenv("PATH") : "");
  try {
    pid_ = pgid_ = SpawnFlightStack(line, socket_path_, path_env);
  } catch (const std::runtime_error& e) {
    Fail(e.what());
  }
}

void StackProcess::Accept(Clock::time_point deadline, double timeout_s) {
  while (Clock::now() < deadline) {
    if (Stopping()) Stopped("to connect");
    pollfd pfd{listen_fd_, POLLIN, 0};
    if (::poll(&pfd, 1, static_cast<int>(flight::kStopPollS * 1000.0)) > 0) {
      const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
      if (fd >= 0) {
        channel_ = std::make_unique<flight::Channel>(fd);
        return;
      }
    }
    Reap(0.0, false);
    if (!exit_note_.empty()) Fail(exit_note_ + " before connecting");
  }
  Fail("it did not connect within " + std::to_string(timeout_s) +
       " s (does it read HPA_FLIGHT_SOCKET?)");
}

flight::WaitLimit StackProcess::Limit() {
  return {step_timeout_s_, [this] { return StopDue(); }};
}

void StackProcess::Fail(const std::string& what) const {
  // the text may carry the stack's own bytes (a parse error quotes them): it becomes JSON
  throw ProtocolError(flight::CleanUtf8(who_ + ": " + what));
}

void StackProcess::Cleanup() {
  channel_.reset();
  Reap(Stopping() ? 0.0 : kExitWaitS, true);
  if (!socket_path_.empty()) KillProcessesOfSocket(socket_path_);
  if (listen_fd_ >= 0) ::close(listen_fd_);
  listen_fd_ = -1;
  if (!dir_.empty()) {
    ::unlink(socket_path_.c_str());
    ::rmdir(dir_.c_str());
    dir_.clear();
  }
  socket_path_.clear();
}

bool StackProcess::StopDue() {
  if (!Stopping()) return false;
  if (!stop_due_) stop_due_ = After(kStopGraceS);
  return Clock::now() >= *stop_due_;
}

void StackProcess::Stopped(const std::string& during) {
  failed_ = true;
  Reap(0.0, true);
  throw flight::WaitInterrupted(flight::CleanUtf8("stopped by signal " +
                                                  std::to_string(StopRequested()) +
                                                  " while waiting for " + who_ + " " + during));
}

void StackProcess::Failed(const std::string& step, const ProtocolError& e) {
  failed_ = true;
  std::string what = step + ": " + e.what();
  // a stack that closed the connection is usually exiting: its status names why (an
  // interpreter's shutdown on a loaded machine can take a good part of a second)
  Reap(kExitNoteWaitS, true);
  if (!exit_note_.empty()) what += " (" + exit_note_ + ")";
  Fail(what);
}

void StackProcess::Listen() {
  listen_fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0) Fail(std::string("socket: ") + std::strerror(errno));
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, socket_path_.c_str(), sizeof addr.sun_path - 1);
  if (::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
      ::listen(listen_fd_, 1) != 0) {
    Fail("cannot serve " + socket_path_ + ": " + std::strerror(errno));
  }
}

void StackProcess::Reap(double wait_s, bool stop) {
  if (pid_ <= 0) return;
  const auto deadline = After(wait_s);
  int status = 0;
  while (true) {
    const pid_t r = ::waitpid(pid_, &status, WNOHANG);
    if (r == pid_) {
      pid_ = 0;
      if (WIFEXITED(status)) {
        exit_note_ = "it exited with status " + std::to_string(WEXITSTATUS(status));
      } else if (WIFSIGNALED(status)) {
        exit_note_ = std::string("it was killed by signal ") + std::to_string(WTERMSIG(status)) +
                     " (" + strsignal(WTERMSIG(status)) + ")";
      }
      if (stop) KillGroup();  // anything it left behind
      return;
    }
    if (r < 0 || Clock::now() >= deadline || Stopping()) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  if (stop) {
    KillGroup();
    ::waitpid(pid_, &status, 0);
    pid_ = 0;
  }
}

void StackProcess::KillGroup() const {
  if (pgid_ > 0) ::kill(-pgid_, SIGKILL);
}

}  // namespace hpa::runner
