// The team's separate flight stack(s) over the lockstep protocol (docs/protocol.md, "Teams"):
// one process per vehicle (each started with HPA_VEHICLE set to its index) or one for the whole
// team, each serving its own socket as a single vehicle's stack does (flight_process.h: the
// process group, HPA_FLIGHT_SOCKET, the cleanup). At each control step every stack with views
// gets its team_tick before any reply is read, so per-vehicle stacks compute side by side; the
// replies are read in vehicle order and checked where they arrive.

#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <thread>
#include <utility>

#include "hpa/flight/protocol.h"
#include "hpa/flight/team_protocol.h"
#include "hpa/scenarios/runner.h"
#include "hpa/sim/world.h"
#include "scenarios/src/runner/flight_process.h"
#include "scenarios/src/runner/team_flight_link.h"

namespace hpa::runner {
namespace {

using flight::Channel;
using flight::MessageType;
using flight::ProtocolError;
using Clock = std::chrono::steady_clock;

// How long the waits on a stack go on once a stop was requested (s), as for a single vehicle's.
constexpr double kStopGraceS = 0.2;
// How long a stack that broke the protocol is given to end (s), so the run error can say how.
constexpr double kExitNoteWaitS = 2.0;
// How long a stack may take to connect (s).
constexpr double kConnectTimeoutS = 30.0;

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

// One stack process of the team: its socket, its process and the vehicles it flies.
class TeamStack {
 public:
  // `vehicle_env`: the HPA_VEHICLE it is started with (-1: none, it flies the whole team).
  TeamStack(const ExternalTeamFlightOptions& options, std::vector<int> vehicles, int vehicle_env)
      : options_(options), vehicles_(std::move(vehicles)), vehicle_env_(vehicle_env) {}
  ~TeamStack() { Cleanup(); }
  TeamStack(const TeamStack&) = delete;
  TeamStack& operator=(const TeamStack&) = delete;

  // Serves its socket and starts its process.
  void Start() {
    std::string dir = "/tmp/hpa-flight-" + FlightOwnerTag() + "-XXXXXX";
    if (::mkdtemp(dir.data()) == nullptr) Fail(std::string("mkdtemp: ") + std::strerror(errno));
    dir_ = dir;
    socket_path_ = dir_ + "/lockstep.sock";
    Listen();
    // the vehicle it flies, in its environment beside HPA_FLIGHT_SOCKET
    const std::string command = vehicle_env_ < 0 ? options_.command
                                                 : "HPA_VEHICLE=" + std::to_string(vehicle_env_) +
                                                       "; export HPA_VEHICLE; " + options_.command;
    const std::string path_env =
        ExecutableDir() + ":" + (std::getenv("PATH") ? std::getenv("PATH") : "");
    try {
      pid_ = pgid_ = SpawnFlightStack(command, socket_path_, path_env);
    } catch (const std::runtime_error& e) {
      Fail(e.what());
    }
  }

  // Waits for it to connect until `deadline`, polling for its end and for a stop signal.
  void Accept(Clock::time_point deadline) {
    while (Clock::now() < deadline) {
      if (Stopping()) Stopped("to connect");
      pollfd pfd{listen_fd_, POLLIN, 0};
      if (::poll(&pfd, 1, static_cast<int>(flight::kStopPollS * 1000.0)) > 0) {
        const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
        if (fd >= 0) {
          channel_ = std::make_unique<Channel>(fd);
          return;
        }
      }
      Reap(0.0, false);
      if (!exit_note_.empty()) Fail(exit_note_ + " before connecting");
    }
    Fail("it did not connect within " + std::to_string(kConnectTimeoutS) +
         " s (does it read HPA_FLIGHT_SOCKET?)");
  }

  // Sends its team_hello.
  void SendHello(const flight::TeamHello& hello) {
    Guard(
        [&] {
          channel_->SendJson(MessageType::kTeamHello, flight::TeamHelloToJson(hello), Limit());
        },
        "team_hello");
  }

  // Reads and checks its team_hello_ack.
  flight::TeamHelloAck ReadHelloAck() {
    flight::TeamHelloAck ack;
    Guard(
        [&] {
          ack = flight::ParseTeamHelloAck(channel_->Expect(MessageType::kTeamHelloAck, Limit()),
                                          vehicles_, 1.0 / sim::World::kPhysicsDt_s);
        },
        "team_hello");
    return ack;
  }

  // Sends a team_tick (its reply is read by ReadReply).
  void SendTick(const flight::TeamTick& tick) {
    Guard([&] { channel_->Send(MessageType::kTeamTick, flight::EncodeTeamTick(tick), Limit()); },
          Step(tick.time_s));
  }

  // Reads the reply to `tick` and checks it against it.
  std::vector<flight::TeamVehicleReply> ReadReply(const flight::TeamTick& tick) {
    std::vector<flight::TeamVehicleReply> replies;
    Guard(
        [&] {
          replies =
              flight::DecodeTeamTickReply(channel_->Expect(MessageType::kTeamTickReply, Limit()));
          flight::CheckTeamTickReply(replies, tick);
        },
        Step(tick.time_s));
    return replies;
  }

  // Whether it may be asked for its finish (not failed, not past a stop's grace).
  bool Finishable() { return !failed_ && !StopDue(); }

  // Sends the finish (an empty tick at time_s).
  void SendFinish(double time_s) {
    flight::FlightInputs in;
    in.time_s = time_s;
    Guard([&] { channel_->Send(MessageType::kFinish, flight::EncodeTick(in), Limit()); }, "finish");
  }

  // Reads and checks its finish_reply.
  void ReadFinish() {
    Guard(
        [&] { flight::ParseFinishReply(channel_->Expect(MessageType::kFinishReply, Limit()), 0); },
        "finish");
  }

  // Closes the socket, stops the process (its group and every process carrying its socket) and
  // removes the socket's directory.
  void Cleanup() {
    channel_.reset();
    Reap(Stopping() ? 0.0 : 2.0, true);
    if (!socket_path_.empty()) KillProcessesOfSocket(socket_path_);
    if (listen_fd_ >= 0) ::close(listen_fd_);
    listen_fd_ = -1;
    if (!dir_.empty()) {
      ::unlink(socket_path_.c_str());
      ::rmdir(dir_.c_str());
      dir_.clear();
    }
  }

  const std::vector<int>& vehicles() const { return vehicles_; }

 private:
  // A control step as error messages name it.
  static std::string Step(double time_s) {
    return "team_tick at t = " + std::to_string(time_s) + " s";
  }

  // The stack as error messages name it: its command, and its vehicle when it flies one.
  std::string Who() const {
    return "flight stack '" + options_.command + "'" +
           (vehicle_env_ >= 0 ? " (vehicle " + std::to_string(vehicle_env_) + ")" : "");
  }

  [[noreturn]] void Fail(const std::string& what) const {
    // the text may carry the stack's own bytes (a parse error quotes them): it becomes JSON
    throw ProtocolError(flight::CleanUtf8(Who() + ": " + what));
  }

  // Ends the run as stopped by the requested signal while it waited on the stack.
  [[noreturn]] void Stopped(const std::string& during) {
    failed_ = true;
    Reap(0.0, true);
    throw flight::WaitInterrupted(flight::CleanUtf8("stopped by signal " +
                                                    std::to_string(StopRequested()) +
                                                    " while waiting for " + Who() + " " + during));
  }

  // One message's wait: the step timeout, ended kStopGraceS after a stop was requested.
  flight::WaitLimit Limit() {
    return {options_.step_timeout_s, [this] { return StopDue(); }};
  }

  // Whether a stop was requested kStopGraceS ago or more (from when a wait first saw it).
  bool StopDue() {
    if (!Stopping()) return false;
    const auto now = Clock::now();
    if (!stop_due_) {
      stop_due_ = now + std::chrono::duration_cast<Clock::duration>(
                            std::chrono::duration<double>(kStopGraceS));
    }
    return now >= *stop_due_;
  }

  // Runs `f`; a protocol failure is rethrown naming the stack, the step and, if the process has
  // ended, how; a wait a stop signal ended is rethrown as the stop.
  template <class F>
  void Guard(F&& f, const std::string& step) {
    if (failed_) Fail(step + ": not sent, the flight stack failed before");
    try {
      f();
    } catch (const flight::WaitInterrupted&) {
      Stopped("(" + step + ")");
    } catch (const ProtocolError& e) {
      failed_ = true;
      std::string what = step + ": " + e.what();
      Reap(kExitNoteWaitS, true);
      if (!exit_note_.empty()) what += " (" + exit_note_ + ")";
      Fail(what);
    }
  }

  void Listen() {
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

  // Waits up to wait_s (cut short by a stop signal) for the process to end and notes how it
  // ended; if it has not and `stop` is set, kills its process group.
  void Reap(double wait_s, bool stop) {
    if (pid_ <= 0) return;
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                             std::chrono::duration<double>(wait_s));
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
        if (stop && pgid_ > 0) ::kill(-pgid_, SIGKILL);  // anything it left behind
        return;
      }
      if (r < 0 || Clock::now() >= deadline || Stopping()) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    if (stop) {
      if (pgid_ > 0) ::kill(-pgid_, SIGKILL);
      ::waitpid(pid_, &status, 0);
      pid_ = 0;
    }
  }

  const ExternalTeamFlightOptions& options_;
  std::vector<int> vehicles_;  // the vehicles it flies, ascending
  int vehicle_env_;            // its HPA_VEHICLE (-1: none)
  std::string dir_, socket_path_, exit_note_;
  int listen_fd_ = -1;
  pid_t pid_ = 0, pgid_ = 0;
  std::unique_ptr<Channel> channel_;
  bool failed_ = false;                        // a message failed: the stack is not asked again
  std::optional<Clock::time_point> stop_due_;  // waits end then (a stop)
};

// The team's separate stacks: one per vehicle, or one for all.
class ExternalTeamFlight final : public TeamFlightLink {
 public:
  ExternalTeamFlight(const CooperativeTeam& team, const ExternalTeamFlightOptions& options)
      : options_(options) {
    const int n = static_cast<int>(team.vehicles.size());
    if (options_.per_vehicle) {
      for (int i = 0; i < n; ++i)
        stacks_.push_back(std::make_unique<TeamStack>(options_, std::vector<int>{i}, i));
    } else {
      std::vector<int> all;
      for (int i = 0; i < n; ++i) all.push_back(i);
      stacks_.push_back(std::make_unique<TeamStack>(options_, all, -1));
    }
    // what earlier runs of killed hpa processes left behind, before this run adds its own
    RemoveStaleFlightRuns();
    // every process started first, so they start up side by side
    for (const auto& s : stacks_) s->Start();
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                             std::chrono::duration<double>(kConnectTimeoutS));
    for (const auto& s : stacks_) s->Accept(deadline);
    flight::TeamHello hello;
    hello.scenario = options_.scenario;
    hello.seed = options_.seed;
    hello.controller = options_.controller;
    hello.team = team;
    hello.reference = options_.reference;
    for (const auto& s : stacks_) {
      hello.vehicles = s->vehicles();
      s->SendHello(hello);
    }
    for (size_t k = 0; k < stacks_.size(); ++k) {
      const flight::TeamHelloAck ack = stacks_[k]->ReadHelloAck();
      if (k == 0) {
        name_ = ack.name;
        // a stack that names no controller flies its own: its name labels the run
        controller_ = !ack.controller.empty() ? ack.controller : ack.name;
        rate_hz_ = ack.control_rate_hz;
      } else if (ack.control_rate_hz != rate_hz_) {
        throw ProtocolError("flight stack '" + options_.command + "': vehicle " +
                            std::to_string(k) + "'s stack runs its controller at " +
                            std::to_string(ack.control_rate_hz) + " Hz, vehicle 0's at " +
                            std::to_string(rate_hz_) + " Hz (a team shares one control rate)");
      }
    }
  }

  std::vector<std::optional<TeamReply>> Step(
      const std::vector<std::optional<TeamView>>& views) override {
    std::vector<std::optional<TeamReply>> replies(views.size());
    // every stack's tick goes out before any reply is read
    std::vector<flight::TeamTick> ticks(stacks_.size());
    for (size_t k = 0; k < stacks_.size(); ++k) {
      flight::TeamTick& tick = ticks[k];
      for (const int i : stacks_[k]->vehicles()) {
        const std::optional<TeamView>& view = views[static_cast<size_t>(i)];
        if (!view) continue;
        tick.time_s = view->time_s;
        tick.views.push_back({i, *view});
      }
      if (!tick.views.empty()) stacks_[k]->SendTick(tick);
      last_time_s_ = std::max(last_time_s_, tick.time_s);
    }
    for (size_t k = 0; k < stacks_.size(); ++k) {
      if (ticks[k].views.empty()) continue;
      for (const flight::TeamVehicleReply& r : stacks_[k]->ReadReply(ticks[k])) {
        TeamReply& reply = replies[static_cast<size_t>(r.vehicle)].emplace();
        reply.output = r.output;
        reply.cable_taut = r.cable_taut;
      }
    }
    return replies;
  }

  double RateHz() const override { return rate_hz_; }
  std::string name() const override { return name_; }
  std::string controller() const override { return controller_; }

  void Finish() override {
    std::vector<TeamStack*> asked;
    for (const auto& s : stacks_) {
      if (!s->Finishable()) continue;
      s->SendFinish(last_time_s_);
      asked.push_back(s.get());
    }
    for (TeamStack* s : asked) s->ReadFinish();
  }

 private:
  ExternalTeamFlightOptions options_;
  std::vector<std::unique_ptr<TeamStack>> stacks_;  // in vehicle order
  std::string name_ = "external", controller_ = "external";
  double rate_hz_ = 0.0;      // the stacks' control rate (Hz)
  double last_time_s_ = 0.0;  // the last control step's time
};

}  // namespace

std::unique_ptr<TeamFlightLink> StartExternalTeamFlight(const CooperativeTeam& team,
                                                        const ExternalTeamFlightOptions& options) {
  return std::make_unique<ExternalTeamFlight>(team, options);
}

}  // namespace hpa::runner
