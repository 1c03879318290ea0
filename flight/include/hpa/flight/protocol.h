#pragma once
// The lockstep wire protocol between the simulator and a flight stack (docs/protocol.md): the
// simulator serves a Unix-domain stream socket, the flight stack connects, and each tick of the
// simulated clock is one request (the tick's sensor messages) and one reply (the estimate and,
// when the controller ran, its command), so simulated time waits for the flight code. Rendered
// camera frames travel through a shared-memory ring named in the hello. Numbers are
// little-endian IEEE doubles and unsigned 32-bit integers, so both sides see the same bits.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "hpa/flight/flight_stack.h"

namespace hpa::flight {

/// The protocol's version: the hello carries it, and a peer speaking another one is refused.
constexpr uint32_t kProtocolVersion = 1;
/// First four bytes of every message ("HPAF").
constexpr uint32_t kMagic = 0x46415048;
/// Largest message body accepted (a malformed length is refused before it is allocated).
constexpr uint32_t kMaxMessageBytes = 64u << 20;

/// The message kinds; each message is a 12-byte header (magic, type, body length) and a body.
enum class MessageType : uint32_t {
  kHello = 1,        // simulator -> flight stack: JSON (version, config, rates, camera ring)
  kHelloAck = 2,     // flight stack -> simulator: JSON (version, name, control rate)
  kTick = 3,         // simulator -> flight stack: one tick's inputs (binary)
  kTickReply = 4,    // flight stack -> simulator: the estimate and command (binary)
  kFinish = 5,       // simulator -> flight stack: the last inputs of the run (binary, a tick)
  kFinishReply = 6,  // flight stack -> simulator: JSON (estimator health)
  kError = 7,        // either way: UTF-8 text naming what went wrong; the peer stops
};

/// A malformed, unexpected or failed message (the text names what was wrong).
class ProtocolError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Name of a message type for errors ("hello", "tick", ...).
std::string MessageTypeName(MessageType type);

/// Encodes one tick's inputs (frames as their slot and capture time).
std::vector<uint8_t> EncodeTick(const FlightInputs& in);
/// Decodes a tick; frames get their slot and capture time (no pixels: the caller maps slots).
FlightInputs DecodeTick(const std::vector<uint8_t>& body);
/// Encodes a tick's reply.
std::vector<uint8_t> EncodeReply(const FlightOutputs& out);
/// Decodes a tick's reply; throws ProtocolError for a non-finite command or estimate, or an
/// unknown status.
FlightOutputs DecodeReply(const std::vector<uint8_t>& body);

/// FlightConfig as JSON (the hello's "config"); doubles keep every bit.
nlohmann::json ConfigToJson(const FlightConfig& config);
/// FlightConfig from the hello's "config"; throws ProtocolError naming a missing or bad key.
FlightConfig ConfigFromJson(const nlohmann::json& j);

/// One connected stream socket with message framing and a per-message time limit.
class Channel {
 public:
  /// Takes ownership of a connected socket.
  explicit Channel(int fd) : fd_(fd) {}
  ~Channel();
  Channel(const Channel&) = delete;
  Channel& operator=(const Channel&) = delete;

  /// Sends one message; throws ProtocolError if the peer has gone.
  void Send(MessageType type, const std::vector<uint8_t>& body);
  /// Sends a JSON message.
  void SendJson(MessageType type, const nlohmann::json& j);
  /// Receives one message within timeout_s (<= 0: no limit); throws ProtocolError on a timeout,
  /// a closed peer, a bad magic or an oversized length. An kError message is thrown as its text.
  MessageType Receive(std::vector<uint8_t>* body, double timeout_s);
  /// Receives a message that must be of `type` (ProtocolError naming both otherwise).
  std::vector<uint8_t> Expect(MessageType type, double timeout_s);
  int fd() const { return fd_; }

 private:
  void ReadExact(uint8_t* data, size_t n, double timeout_s);
  int fd_;
};

/// Connects to the simulator's socket at `path`; throws ProtocolError if it cannot.
int ConnectUnix(const std::string& path);

}  // namespace hpa::flight
