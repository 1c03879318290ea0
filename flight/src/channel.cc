// The lockstep protocol's socket: a Channel frames messages (a 12-byte header, then the body) on a
// connected Unix-domain stream socket, sends and receives each within its time limit and stop
// check, and reads ahead in large reads; ConnectUnix connects a flight stack to the simulator.

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hpa/flight/protocol.h"

namespace hpa::flight {

Channel::~Channel() {
  if (fd_ >= 0) ::close(fd_);
}

namespace {

using Clock = std::chrono::steady_clock;

// One message's wait on a socket: the deadline of the whole message and the stop check.
class MessageWait {
 public:
  explicit MessageWait(const WaitLimit& limit) : limit_(limit) {
    if (limit.timeout_s > 0) {
      deadline_ = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                     std::chrono::duration<double>(limit.timeout_s));
    }
  }
  // Waits until `fd` is ready for `events` (or has failed: the read or write then says how);
  // false when the deadline passed first; WaitInterrupted when the stop check ends the wait.
  bool Ready(int fd, short events) const {
    while (true) {
      if (limit_.stop && limit_.stop()) throw WaitInterrupted("the wait was interrupted");
      int slice_ms = limit_.stop ? static_cast<int>(kStopPollS * 1000.0) : -1;
      if (deadline_) {
        const double left_ms =
            std::chrono::duration<double, std::milli>(*deadline_ - Clock::now()).count();
        if (left_ms <= 0.0) return false;
        const int left = static_cast<int>(std::min(std::ceil(left_ms), 3.6e6));
        slice_ms = slice_ms < 0 ? left : std::min(slice_ms, left);
      }
      pollfd pfd{fd, events, 0};
      const int ready = ::poll(&pfd, 1, slice_ms);
      if (ready > 0) return true;
      if (ready < 0 && errno != EINTR) {
        throw ProtocolError(std::string("poll: ") + std::strerror(errno));
      }
    }
  }
  double timeout_s() const { return limit_.timeout_s; }

 private:
  const WaitLimit& limit_;
  std::optional<Clock::time_point> deadline_;  // none: no limit
};

// Bytes a read asks for at most: many small messages arrive in one read.
constexpr size_t kReadAheadBytes = 64 * 1024;

// A peer's error text as a run error may carry it: its own words, which may not be UTF-8, made
// UTF-8 (they end up in JSON), cut to its first kMaxErrorTextBytes (at a character's start)
// with its full length stated.
std::string ErrorText(const std::vector<uint8_t>& body) {
  const std::string_view text(reinterpret_cast<const char*>(body.data()), body.size());
  if (text.size() <= kMaxErrorTextBytes) return CleanUtf8(text);
  size_t cut = kMaxErrorTextBytes;
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
  return CleanUtf8(text.substr(0, cut)) + " ... (error text of " + std::to_string(text.size()) +
         " bytes, first " + std::to_string(cut) + " shown)";
}

}  // namespace

bool Channel::ReadExact(uint8_t* data, size_t n, const void* wait_ptr, size_t* got) {
  const MessageWait& wait = *static_cast<const MessageWait*>(wait_ptr);
  if (in_.size() < kReadAheadBytes) in_.resize(kReadAheadBytes);
  while (n > 0) {
    // what was read ahead first
    if (in_begin_ < in_end_) {
      const size_t k = std::min(n, in_end_ - in_begin_);
      std::memcpy(data, in_.data() + in_begin_, k);
      in_begin_ += k;
      data += k;
      n -= k;
      *got += k;
      continue;
    }
    // a large body straight into its place, a small one (or a header) through the read-ahead
    const bool direct = n >= kReadAheadBytes;
    uint8_t* into = direct ? data : in_.data();
    const ssize_t k = ::recv(fd_, into, direct ? n : kReadAheadBytes, MSG_DONTWAIT);
    if (k < 0 && errno == EINTR) continue;
    if (k < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      if (!wait.Ready(fd_, POLLIN)) return false;
      continue;
    }
    if (k <= 0) throw ProtocolError("the peer closed the connection");
    if (direct) {
      data += k;
      n -= static_cast<size_t>(k);
      *got += static_cast<size_t>(k);
    } else {
      in_begin_ = 0;
      in_end_ = static_cast<size_t>(k);
    }
  }
  return true;
}

void Channel::Queue(MessageType type, const std::vector<uint8_t>& body) {
  const uint32_t header[3] = {kMagic, static_cast<uint32_t>(type),
                              static_cast<uint32_t>(body.size())};
  const auto* h = reinterpret_cast<const uint8_t*>(header);
  out_.insert(out_.end(), h, h + sizeof header);
  out_.insert(out_.end(), body.begin(), body.end());
  out_last_type_ = type;
}

void Channel::Send(MessageType type, const std::vector<uint8_t>& body, const WaitLimit& limit) {
  Queue(type, body);
  Flush(limit);
}

void Channel::Flush(const WaitLimit& limit) {
  const MessageWait wait(limit);
  // a failure names the last message queued (the one a reply is awaited for)
  const std::string what = MessageTypeName(out_last_type_) + " message";
  size_t sent = 0;
  while (sent < out_.size()) {
    const ssize_t k =
        ::send(fd_, out_.data() + sent, out_.size() - sent, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (k < 0 && errno == EINTR) continue;
    if (k < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      bool ready = false;
      try {
        ready = wait.Ready(fd_, POLLOUT);
      } catch (...) {
        out_.clear();
        throw;
      }
      if (!ready) {
        out_.clear();
        throw ProtocolError("the peer took no " + what + " within " +
                            std::to_string(limit.timeout_s) + " s (it reads nothing)");
      }
      continue;
    }
    if (k <= 0) {
      const std::string why = std::strerror(errno);
      out_.clear();
      throw ProtocolError("the peer closed the connection while a " + what + " was sent (" + why +
                          ")");
    }
    sent += static_cast<size_t>(k);
  }
  out_.clear();
}

void Channel::SendJson(MessageType type, const nlohmann::json& j, const WaitLimit& limit) {
  CheckJsonMessage(type, j);
  const std::string text = j.dump();
  Send(type, std::vector<uint8_t>(text.begin(), text.end()), limit);
}

MessageType Channel::Receive(std::vector<uint8_t>* body, const WaitLimit& limit) {
  // one deadline for the header and the body: a peer that dribbles a message is as late as
  // one that sends none
  const MessageWait wait(limit);
  size_t got = 0;
  uint32_t header[3];
  const auto late = [&](size_t expected) {
    std::string what = "no answer within " + std::to_string(limit.timeout_s) + " s";
    if (got > 0) {
      what += " (" + std::to_string(got) + " of the message's " + std::to_string(expected) +
              " bytes had arrived)";
    }
    return ProtocolError(what);
  };
  if (!ReadExact(reinterpret_cast<uint8_t*>(header), sizeof header, &wait, &got)) {
    throw late(sizeof header);
  }
  if (header[0] != kMagic) {
    throw ProtocolError("a message without the protocol's magic (not an hpa lockstep peer?)");
  }
  if (header[2] > kMaxMessageBytes) {
    throw ProtocolError("a message of " + std::to_string(header[2]) + " bytes (at most " +
                        std::to_string(kMaxMessageBytes) + ")");
  }
  body->resize(header[2]);
  if (!ReadExact(body->data(), body->size(), &wait, &got)) throw late(sizeof header + header[2]);
  const auto type = static_cast<MessageType>(header[1]);
  if (type == MessageType::kError) throw ProtocolError("the peer reported: " + ErrorText(*body));
  return type;
}

bool Channel::HasUnread() {
  if (in_begin_ < in_end_) return true;
  uint8_t byte = 0;
  while (true) {
    const ssize_t k = ::recv(fd_, &byte, 1, MSG_PEEK | MSG_DONTWAIT);
    if (k < 0 && errno == EINTR) continue;
    return k > 0;  // 0: the peer closed (the next receive says so); < 0: nothing waits
  }
}

MessageType Channel::Receive(std::vector<uint8_t>* body, double timeout_s) {
  return Receive(body, WaitLimit{timeout_s, {}});
}

std::vector<uint8_t> Channel::Expect(MessageType type, const WaitLimit& limit) {
  std::vector<uint8_t> body;
  const MessageType got = Receive(&body, limit);
  if (got != type) {
    throw ProtocolError("expected a " + MessageTypeName(type) + " message, got " +
                        MessageTypeName(got));
  }
  return body;
}

std::vector<uint8_t> Channel::Expect(MessageType type, double timeout_s) {
  return Expect(type, WaitLimit{timeout_s, {}});
}

int ConnectUnix(const std::string& path) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (path.size() >= sizeof addr.sun_path) throw ProtocolError("socket path too long: " + path);
  std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw ProtocolError(std::string("socket: ") + std::strerror(errno));
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    const std::string why = std::strerror(errno);
    ::close(fd);
    throw ProtocolError("cannot connect to " + path + ": " + why);
  }
  return fd;
}

}  // namespace hpa::flight
