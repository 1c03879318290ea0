#include "scenarios/src/runner/flight_link.h"

#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <thread>

#include "hpa/scenarios/runner.h"
#include "scenarios/src/runner/flight_process.h"
#include "scenarios/src/runner/frame_ring.h"

namespace hpa::runner {
namespace {

using flight::Channel;
using flight::MessageType;
using flight::ProtocolError;

class InProcessFlight final : public FlightLink {
 public:
  explicit InProcessFlight(const flight::FlightConfig& config) : stack_(config) {}
  flight::FlightOutputs Step(const flight::FlightInputs& in) override { return stack_.Step(in); }
  ControlOutput AwaitCommand() override { return stack_.AwaitCommand(); }
  FlightFinish Finish(const flight::FlightInputs& pending) override {
    FlightFinish f;
    f.frames_detected = stack_.Finish(pending);
    f.estimator = stack_.config().ground_truth ? "" : stack_.config().estimator;
    f.estimator_health = stack_.EstimatorHealth();
    return f;
  }
  std::string name() const override { return "in_process"; }
  std::string controller() const override { return stack_.config().controller.type; }
  double control_rate_hz() const override { return stack_.control_rate_hz(); }

 private:
  flight::FlightStack stack_;
};

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

// How long the waits on a stack go on once a stop was requested (s): a stack that answers
// promptly completes the message in flight and its finish report, a hung one is abandoned.
constexpr double kStopGraceS = 0.2;

// A separate flight stack: its process, the socket it connected to and the frame ring.
class ExternalFlight final : public FlightLink {
 public:
  ExternalFlight(const flight::FlightConfig& config, const ExternalFlightOptions& options)
      : options_(options) {
    try {
      Start(config);
    } catch (...) {
      Cleanup();
      throw;
    }
  }

  ~ExternalFlight() override { Cleanup(); }

  void Start(const flight::FlightConfig& config) {
    const ExternalFlightOptions& options = options_;
    // what earlier runs of killed hpa processes left behind, before this run adds its own
    RemoveStaleFlightRuns();
    static std::atomic<int> counter{0};
    const int n = counter++;
    const std::string owner = FlightOwnerTag();
    std::string dir = "/tmp/hpa-flight-" + owner + "-XXXXXX";
    if (::mkdtemp(dir.data()) == nullptr) Fail(std::string("mkdtemp: ") + std::strerror(errno));
    dir_ = dir;
    socket_path_ = dir_ + "/lockstep.sock";
    Listen();
    if (options.frames.slots > 0) {
      ring_ = std::make_unique<FrameRing>("/hpa-flight-" + owner + "-" + std::to_string(n),
                                          options.frames.slots, options.frames.width_px,
                                          options.frames.height_px);
    }
    Spawn();
    Accept();
    nlohmann::json hello = {{"protocol_version", flight::kProtocolVersion},
                            {"scenario", options.scenario},
                            {"seed", options.seed},
                            {"rates", options.rates},
                            {"config", flight::ConfigToJson(config)}};
    if (ring_) {
      hello["camera"] = {{"ring", ring_->name()},
                         {"slots", options.frames.slots},
                         {"width_px", options.frames.width_px},
                         {"height_px", options.frames.height_px},
                         {"slot_bytes", ring_->slot_bytes()}};
    }
    Guard(
        [&] {
          channel_->SendJson(MessageType::kHello, hello, Limit());
          const flight::HelloAck ack =
              flight::ParseHelloAck(channel_->Expect(MessageType::kHelloAck, Limit()));
          name_ = ack.name;
          // a stack that names no controller flies its own: its name labels the run
          controller_ = !ack.controller.empty() ? ack.controller
                        : !ack.name.empty()     ? ack.name
                                                : "external";
          control_rate_hz_ = ack.control_rate_hz;
        },
        "hello");
  }

  // Closes the socket (a stack waiting on it sees the end), stops the process (its group and
  // every process carrying its socket), frees the ring and removes the socket's directory.
  void Cleanup() {
    channel_.reset();
    Reap(Stopping() ? 0.0 : 2.0, true);
    if (!socket_path_.empty()) KillProcessesOfSocket(socket_path_);
    ring_.reset();
    if (listen_fd_ >= 0) ::close(listen_fd_);
    listen_fd_ = -1;
    if (!dir_.empty()) {
      ::unlink(socket_path_.c_str());
      ::rmdir(dir_.c_str());
      dir_.clear();
    }
  }

  flight::FlightOutputs Step(const flight::FlightInputs& in) override {
    flight::FlightOutputs out;
    messages_so_far_ += in.imu.size() + in.vio.size() + in.detections.size() + in.frames.size();
    Guard(
        [&] {
          if (ring_) ring_->Check();  // frames rendered into a ring cut short are never sent
          channel_->Send(MessageType::kTick, flight::EncodeTick(in), Limit());
          out = flight::DecodeReply(channel_->Expect(MessageType::kTickReply, Limit()));
          flight::ReplyBounds bounds;
          bounds.frames = in.frames.size();
          bounds.estimate_needed = in.need_estimate;
          bounds.messages_so_far = messages_so_far_;
          if (ring_) {
            bounds.image_width_px = options_.frames.width_px;
            bounds.image_height_px = options_.frames.height_px;
          }
          flight::CheckReply(out, bounds);
        },
        "tick at t = " + std::to_string(in.time_s) + " s");
    return out;
  }

  FlightFinish Finish(const flight::FlightInputs& pending) override {
    FlightFinish f;
    // a stack that failed (or a wait a stop ended) is not asked again: the run error says why;
    // after a stop, only within its grace
    if (failed_ || StopDue()) return f;
    const flight::WaitLimit limit = Limit();
    Guard(
        [&] {
          if (ring_) ring_->Check();
          channel_->Send(MessageType::kFinish, flight::EncodeTick(pending), limit);
          const flight::FinishReply reply = flight::ParseFinishReply(
              channel_->Expect(MessageType::kFinishReply, limit), pending.frames.size());
          f.estimator = reply.estimator;
          f.frames_detected = reply.frames_detected;
          f.estimator_health = reply.estimator_health;
        },
        "finish");
    return f;
  }

  cv::Mat* NextFrameSlot(int* slot) override {
    if (!ring_) return nullptr;
    Guard([&] { ring_->Check(); }, "frame ring");
    *slot = next_slot_;
    next_slot_ = (next_slot_ + 1) % options_.frames.slots;
    return ring_->Slot(*slot);
  }
  bool wants_reference() const override { return true; }
  std::string name() const override { return name_; }
  std::string controller() const override { return controller_; }
  double control_rate_hz() const override { return control_rate_hz_; }

 private:
  [[noreturn]] void Fail(const std::string& what) const {
    // the text may carry the stack's own bytes (a parse error quotes them): it becomes JSON
    throw ProtocolError(flight::CleanUtf8("flight stack '" + options_.command + "': " + what));
  }

  // Ends the run as stopped by the requested signal while it waited on the stack (`during`
  // says for what); the stack is killed and not asked again.
  [[noreturn]] void Stopped(const std::string& during) {
    failed_ = true;
    Reap(0.0, true);
    throw flight::WaitInterrupted(
        flight::CleanUtf8("stopped by signal " + std::to_string(StopRequested()) +
                          " while waiting for flight stack '" + options_.command + "' " + during));
  }

  // One message's wait: the step timeout, ended kStopGraceS after a stop was requested.
  flight::WaitLimit Limit() {
    return {options_.step_timeout_s, [this] { return StopDue(); }};
  }

  // Whether a stop was requested kStopGraceS ago or more (counted from when a wait or the
  // finish first saw it).
  bool StopDue() {
    if (!Stopping()) return false;
    const auto now = std::chrono::steady_clock::now();
    if (!stop_due_) {
      stop_due_ = now + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(kStopGraceS));
    }
    return now >= *stop_due_;
  }

  // Runs `f`; a protocol failure is rethrown naming the command, the step and, if the process
  // has ended, how; a wait a stop signal ended is rethrown as the stop.
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
      Reap(0.2, true);
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

  void Spawn() {
    const std::string path_env =
        ExecutableDir() + ":" + (std::getenv("PATH") ? std::getenv("PATH") : "");
    try {
      pid_ = pgid_ = SpawnFlightStack(options_.command, socket_path_, path_env);
    } catch (const std::runtime_error& e) {
      Fail(e.what());
    }
  }

  // Waits for the stack to connect, polling for its end and for a stop signal.
  void Accept() {
    using Clock = std::chrono::steady_clock;
    const auto deadline = Clock::now() + std::chrono::duration<double>(options_.connect_timeout_s);
    while (Clock::now() < deadline) {
      if (Stopping()) Stopped("to connect");
      pollfd pfd{listen_fd_, POLLIN, 0};
      const int ready = ::poll(&pfd, 1, static_cast<int>(flight::kStopPollS * 1000.0));
      if (ready > 0) {
        const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
        if (fd >= 0) {
          channel_ = std::make_unique<Channel>(fd);
          return;
        }
      }
      Reap(0.0, false);
      if (!exit_note_.empty()) Fail(exit_note_ + " before connecting");
    }
    Fail("it did not connect within " + std::to_string(options_.connect_timeout_s) +
         " s (does it read HPA_FLIGHT_SOCKET?)");
  }

  // Waits up to wait_s (cut short by a stop signal) for the process to end and notes how it
  // ended; if it has not and `stop` is set, kills its process group.
  void Reap(double wait_s, bool stop) {
    if (pid_ <= 0) return;
    using Clock = std::chrono::steady_clock;
    const auto deadline = Clock::now() + std::chrono::duration<double>(wait_s);
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
  void KillGroup() const {
    if (pgid_ > 0) ::kill(-pgid_, SIGKILL);
  }

  ExternalFlightOptions options_;
  std::string dir_, socket_path_, name_ = "external", controller_ = "external", exit_note_;
  double control_rate_hz_ = 0.0;  // from the hello_ack (0: not stated)
  int listen_fd_ = -1;
  pid_t pid_ = 0, pgid_ = 0;
  std::unique_ptr<Channel> channel_;
  std::unique_ptr<FrameRing> ring_;  // the rendered frames, when they cross
  int next_slot_ = 0;
  uint64_t messages_so_far_ = 0;  // sensor messages sent (the estimator counters' bound)
  bool failed_ = false;           // a message failed: the stack is not asked again
  std::optional<std::chrono::steady_clock::time_point> stop_due_;  // waits end then (a stop)
};

}  // namespace

std::unique_ptr<FlightLink> MakeInProcessFlight(const flight::FlightConfig& config) {
  return std::make_unique<InProcessFlight>(config);
}

std::unique_ptr<FlightLink> StartExternalFlight(const flight::FlightConfig& config,
                                                const ExternalFlightOptions& options) {
  return std::make_unique<ExternalFlight>(config, options);
}

}  // namespace hpa::runner
