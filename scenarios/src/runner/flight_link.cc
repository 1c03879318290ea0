#include "scenarios/src/runner/flight_link.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <thread>

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
    static std::atomic<int> counter{0};
    const int n = counter++;
    char dir[] = "/tmp/hpa-flight-XXXXXX";
    if (::mkdtemp(dir) == nullptr) Fail(std::string("mkdtemp: ") + std::strerror(errno));
    dir_ = dir;
    socket_path_ = dir_ + "/lockstep.sock";
    Listen();
    if (options.frames.slots > 0) {
      ring_name_ = "/hpa-flight-" + std::to_string(::getpid()) + "-" + std::to_string(n);
      MapRing(options.frames);
    }
    Spawn();
    Accept();
    nlohmann::json hello = {{"protocol_version", flight::kProtocolVersion},
                            {"scenario", options.scenario},
                            {"seed", options.seed},
                            {"rates", options.rates},
                            {"config", flight::ConfigToJson(config)}};
    if (!ring_name_.empty()) {
      hello["camera"] = {{"ring", ring_name_},
                         {"slots", options.frames.slots},
                         {"width_px", options.frames.width_px},
                         {"height_px", options.frames.height_px},
                         {"slot_bytes", slot_bytes_}};
    }
    Guard(
        [&] {
          channel_->SendJson(MessageType::kHello, hello);
          const std::vector<uint8_t> ack =
              channel_->Expect(MessageType::kHelloAck, options_.step_timeout_s);
          nlohmann::json j;
          try {
            j = nlohmann::json::parse(ack.begin(), ack.end());
            const uint32_t version = j.at("protocol_version").get<uint32_t>();
            if (version != flight::kProtocolVersion) {
              throw ProtocolError("it speaks protocol version " + std::to_string(version) +
                                  ", this simulator version " +
                                  std::to_string(flight::kProtocolVersion));
            }
            name_ = j.value("name", "external");
            const nlohmann::json rate = j.value("control_rate_hz", nlohmann::json());
            control_rate_hz_ = rate.is_number() ? rate.get<double>() : 0.0;
          } catch (const nlohmann::json::exception& e) {
            throw ProtocolError(std::string("a malformed hello_ack: ") + e.what());
          }
        },
        "hello");
  }

  // Closes the socket (a stack waiting on it sees the end), stops the process, frees the ring
  // and removes the socket's directory.
  void Cleanup() {
    channel_.reset();
    Reap(2.0, true);
    if (ring_ != nullptr) ::munmap(ring_, slot_bytes_ * static_cast<size_t>(options_.frames.slots));
    ring_ = nullptr;
    if (!ring_name_.empty()) ::shm_unlink(ring_name_.c_str());
    if (listen_fd_ >= 0) ::close(listen_fd_);
    listen_fd_ = -1;
    if (!dir_.empty()) {
      ::unlink(socket_path_.c_str());
      ::rmdir(dir_.c_str());
    }
  }

  flight::FlightOutputs Step(const flight::FlightInputs& in) override {
    flight::FlightOutputs out;
    Guard(
        [&] {
          channel_->Send(MessageType::kTick, flight::EncodeTick(in));
          out = flight::DecodeReply(
              channel_->Expect(MessageType::kTickReply, options_.step_timeout_s));
        },
        "tick at t = " + std::to_string(in.time_s) + " s");
    return out;
  }

  FlightFinish Finish(const flight::FlightInputs& pending) override {
    FlightFinish f;
    Guard(
        [&] {
          channel_->Send(MessageType::kFinish, flight::EncodeTick(pending));
          const std::vector<uint8_t> body =
              channel_->Expect(MessageType::kFinishReply, options_.step_timeout_s);
          try {
            const nlohmann::json j = nlohmann::json::parse(body.begin(), body.end());
            f.estimator = j.value("estimator", "");
            f.frames_detected = j.value("frames_detected", 0);
            for (const nlohmann::json& kv : j.value("estimator_health", nlohmann::json::array())) {
              f.estimator_health.emplace_back(kv.at(0).get<std::string>(), kv.at(1).get<double>());
            }
          } catch (const nlohmann::json::exception& e) {
            throw ProtocolError(std::string("a malformed finish_reply: ") + e.what());
          }
        },
        "finish");
    return f;
  }

  cv::Mat* NextFrameSlot(int* slot) override {
    if (ring_ == nullptr) return nullptr;
    *slot = next_slot_;
    next_slot_ = (next_slot_ + 1) % options_.frames.slots;
    return &slot_mats_[static_cast<size_t>(*slot)];
  }
  bool wants_reference() const override { return true; }
  std::string name() const override { return name_; }
  double control_rate_hz() const override { return control_rate_hz_; }

 private:
  [[noreturn]] void Fail(const std::string& what) const {
    throw ProtocolError("flight stack '" + options_.command + "': " + what);
  }

  // Runs `f`; a protocol failure is rethrown naming the command, the step and, if the process
  // has ended, how.
  template <class F>
  void Guard(F&& f, const std::string& step) {
    if (failed_) Fail(step + ": not sent, the flight stack failed before");
    try {
      f();
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

  void MapRing(const FrameRingSpec& frames) {
    slot_bytes_ = static_cast<size_t>(frames.width_px) * frames.height_px * 3;
    const size_t bytes = slot_bytes_ * static_cast<size_t>(frames.slots);
    const int fd = ::shm_open(ring_name_.c_str(), O_CREAT | O_EXCL | O_RDWR, 0600);
    if (fd < 0) Fail("shm_open " + ring_name_ + ": " + std::strerror(errno));
    if (::ftruncate(fd, static_cast<off_t>(bytes)) != 0) {
      ::close(fd);
      Fail("cannot size the frame ring: " + std::string(std::strerror(errno)));
    }
    void* p = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    ::close(fd);
    if (p == MAP_FAILED) Fail("cannot map the frame ring: " + std::string(std::strerror(errno)));
    ring_ = static_cast<uint8_t*>(p);
    for (int i = 0; i < frames.slots; ++i) {
      slot_mats_.emplace_back(frames.height_px, frames.width_px, CV_8UC3,
                              ring_ + slot_bytes_ * static_cast<size_t>(i));
    }
  }

  void Spawn() {
    const std::string path_env =
        ExecutableDir() + ":" + (std::getenv("PATH") ? std::getenv("PATH") : "");
    pid_ = ::fork();
    if (pid_ < 0) Fail(std::string("fork: ") + std::strerror(errno));
    if (pid_ == 0) {
      ::setpgid(0, 0);  // its own process group: the whole command can be stopped
      ::dup2(2, 1);     // its output goes to stderr, never into hpa's stdout
      ::setenv("HPA_FLIGHT_SOCKET", socket_path_.c_str(), 1);
      ::setenv("PATH", path_env.c_str(), 1);
      ::execl("/bin/sh", "sh", "-c", options_.command.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    ::setpgid(pid_, pid_);
    pgid_ = pid_;
  }

  void Accept() {
    using Clock = std::chrono::steady_clock;
    const auto deadline = Clock::now() + std::chrono::duration<double>(options_.connect_timeout_s);
    while (Clock::now() < deadline) {
      pollfd pfd{listen_fd_, POLLIN, 0};
      const int ready = ::poll(&pfd, 1, 100);
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

  // Waits up to wait_s for the process to end and notes how it ended; if it has not and `stop`
  // is set, kills its process group.
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
      if (r < 0 || Clock::now() >= deadline) break;
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
  std::string dir_, socket_path_, ring_name_, name_ = "external", exit_note_;
  double control_rate_hz_ = 0.0;  // from the hello_ack (0: not stated)
  int listen_fd_ = -1;
  pid_t pid_ = 0, pgid_ = 0;
  std::unique_ptr<Channel> channel_;
  uint8_t* ring_ = nullptr;
  size_t slot_bytes_ = 0;
  std::vector<cv::Mat> slot_mats_;
  int next_slot_ = 0;
  bool failed_ = false;  // a message failed: the stack is not asked again
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
