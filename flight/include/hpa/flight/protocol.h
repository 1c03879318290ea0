#pragma once
// The lockstep wire protocol between the simulator and a flight stack (docs/protocol.md): the
// simulator serves a Unix-domain stream socket, the flight stack connects, and each tick of the
// simulated clock is one request (the tick's sensor messages) and one reply (the estimate and,
// when the controller ran, its command), so simulated time waits for the flight code. Rendered
// camera frames travel through a shared-memory ring named in the hello. Numbers are
// little-endian IEEE doubles and 32-bit integers, so both sides see the same bits. Every binary
// message's fields (order, type, unit, range, refusal text, doc) are declared once, in the
// message table python/hpa_sim/messages.json: this library compiles it in and its encoder and
// decoder walk it; the Python client reads the same file.

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "hpa/autopilot/autopilot.h"
#include "hpa/flight/flight_stack.h"

namespace hpa::flight {

/// The protocol's version: the hello carries it, and a peer speaking another one is refused.
constexpr uint32_t kProtocolVersion = 1;
/// First four bytes of every message ("HPAF").
constexpr uint32_t kMagic = 0x46415048;
/// Largest message body accepted (a malformed length is refused before it is allocated).
constexpr uint32_t kMaxMessageBytes = 64u << 20;
/// Most bytes of a peer's error text a receiver keeps (its head): the text becomes a run error in
/// metrics.json, which a stack's megabytes would swamp; its full length is stated beside it.
constexpr size_t kMaxErrorTextBytes = 4096;

/// The message kinds; each message is a 12-byte header (magic, type, body length) and a body.
enum class MessageType : uint32_t {
  kHello = 1,        // simulator -> flight stack: JSON (version, config, rates, camera ring)
  kHelloAck = 2,     // flight stack -> simulator: JSON (version, name, control rate)
  kTick = 3,         // simulator -> flight stack: one tick's inputs (binary)
  kTickReply = 4,    // flight stack -> simulator: the estimate and command (binary)
  kFinish = 5,       // simulator -> flight stack: the last inputs of the run (binary, a tick)
  kFinishReply = 6,  // flight stack -> simulator: JSON (estimator health)
  kError = 7,        // either way: UTF-8 text naming what went wrong; the peer stops
  kDetect = 8,       // simulator -> a stack detecting at capture: a frame being captured (binary)
  kDetectReply = 9,  // flight stack -> simulator: its detection, or what to read out (binary)
  kRateTick = 10,    // simulator -> a stack owning the rate loop: one step of it due (binary)
  kRateReply = 11,   // flight stack -> simulator: that step's rotor speed commands (binary)

  // a team's stacks (one per vehicle, or one for the team)
  kTeamHello = 12,      // simulator -> stack: JSON (its vehicles, the team, the reference)
  kTeamHelloAck = 13,   // stack -> simulator: JSON (version, name, control rate, vehicles)
  kTeamTick = 14,       // simulator -> stack: its vehicles' views (binary)
  kTeamTickReply = 15,  // stack -> simulator: their commands (binary)
};

/// A malformed, unexpected or failed message (the text names what was wrong).
class ProtocolError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A wait on the peer that its stop check ended early (the simulator was asked to stop).
class WaitInterrupted : public ProtocolError {
 public:
  using ProtocolError::ProtocolError;
};

/// Name of a message type for errors ("hello", "tick", ...).
std::string MessageTypeName(MessageType type);

/// `text` with every byte that is not part of valid UTF-8 replaced by U+FFFD: a peer's text
/// (an error message, a name) can then enter JSON, which must be UTF-8.
std::string CleanUtf8(std::string_view text);

/// Encodes one tick's inputs (frames as their slot and capture time).
std::vector<uint8_t> EncodeTick(const FlightInputs& in);
/// Decodes a tick (or a finish); frames get their slot and capture time (no pixels: the caller
/// maps slots). Throws ProtocolError naming the field and its value for a value outside its
/// declaration in the message table (an unknown flag, mode or bool value, text that is not
/// UTF-8) or a body of the wrong length.
FlightInputs DecodeTick(const std::vector<uint8_t>& body);
/// Encodes a tick's reply.
std::vector<uint8_t> EncodeReply(const FlightOutputs& out);
/// Decodes a tick's reply; throws ProtocolError naming the field and its value for a value the
/// message table refuses: a non-finite command or estimate, an unknown status or state flag, a
/// negative, non-finite or over-an-hour solve time, a negative or non-finite cost, an estimate
/// quaternion of norm outside [0.9, 1.1], a counter past 2^31 - 1. A quaternion within that
/// range but not unit to 1e-9 is renormalised (a unit one keeps every bit).
FlightOutputs DecodeReply(const std::vector<uint8_t>& body);

/// A stack's answer to a detect message (a frame being captured): exactly one of its flags.
struct DetectReply {
  bool has_detection = false;  // `detection` is the frame's: the frame is done
  bool region_wanted = false;  // read out `camera_roi` of the frame and ask again
  bool whole_wanted = false;   // read out the whole frame and ask again
  cv::Rect camera_roi;         // region_wanted: the region to read out (px)
  PayloadDetection detection;  // has_detection: the detection in the pixels read out so far
};

/// Encodes a detect message: the frame being captured (its region and ring slots read out so
/// far; none: the stack is asked which region to read).
std::vector<uint8_t> EncodeDetect(const CameraFrame& frame);
/// Decodes a detect message; throws ProtocolError as DecodeTick does.
CameraFrame DecodeDetect(const std::vector<uint8_t>& body);
/// Encodes a detect_reply.
std::vector<uint8_t> EncodeDetectReply(const DetectReply& reply);
/// Decodes a detect_reply; throws ProtocolError naming the field and value for a value the
/// message table refuses, or for a reply that does not set exactly one of its flags.
DetectReply DecodeDetectReply(const std::vector<uint8_t>& body);

/// One step of the vehicle's rate loop, as the simulator hands it to a stack that owns the loop:
/// what RunLoop would feed its own Autopilot::Update.
struct RateTick {
  double time_s = 0.0;      // simulated time of the step
  BodyRateCommand command;  // the command the loop tracks (after compute + transport latency)
  Eigen::Vector3d w_B_radps = Eigen::Vector3d::Zero();  // rate-gyro sample or estimated body
                                                        // rate, body frame  (3)
};

/// Encodes a rate_tick.
std::vector<uint8_t> EncodeRateTick(const RateTick& tick);
/// Decodes a rate_tick; throws ProtocolError as DecodeTick does.
RateTick DecodeRateTick(const std::vector<uint8_t>& body);
/// Encodes a rate_reply: the stack's Autopilot output of that step.
std::vector<uint8_t> EncodeRateReply(const AutopilotOutput& out);
/// Decodes a rate_reply; throws ProtocolError naming the field and value for a non-finite rotor
/// speed command or a thrust allocated that is not a finite number >= 0.
AutopilotOutput DecodeRateReply(const std::vector<uint8_t>& body);
/// Checks a decoded rate_reply against the vehicle: throws ProtocolError naming the rotor and its
/// speed for a command outside the motors' range [motor_speed_min_radps, motor_speed_max_radps].
void CheckRateReply(const AutopilotOutput& out, const Params& params);

/// The rate loop a stack that owns it runs (the hello's rate_loop): the world profile's
/// rate_loop section and the rate the own loop steps at.
struct RateLoopConfig {
  RateLoopSpec spec;         // which loop, and PX4's parameters
  double own_rate_hz = 0.0;  // the own loop's rate (the IMU's), Hz
};
/// RateLoopConfig as the hello's rate_loop (PX4's parameters by their world-profile keys).
nlohmann::json RateLoopToJson(const RateLoopConfig& config);
/// RateLoopConfig from the hello's rate_loop; throws ProtocolError naming a missing key or a
/// value outside its declared range.
RateLoopConfig RateLoopFromJson(const nlohmann::json& j);

/// The message table (python/hpa_sim/messages.json as compiled in): the framing constants, the
/// message types and every binary message's structs with their fields' types, units, checks
/// and docs.
const nlohmann::json& MessageTable();
/// Checks a JSON message (hello, hello_ack, finish_reply) against its keys in the message table;
/// throws ProtocolError naming a key the table does not declare for it, a required key it lacks,
/// or a value of another JSON type than declared (a nested object's keys likewise).
void CheckJsonMessage(MessageType type, const nlohmann::json& j);
/// Binds every binary message's C++ structs to the message table; throws std::logic_error
/// naming a field or bit of the table no member carries, a member bound to a name the table
/// lacks or to a field of another type, or a struct of the table no message uses.
void CheckMessageBindings();

/// What a tick's reply is checked against: the tick it answers and the run so far.
struct ReplyBounds {
  size_t frames = 0;             // frames the tick delivered (frames_detected's bound)
  bool estimate_needed = false;  // the tick set flag 8 (estimate needed)
  uint64_t messages_so_far = 0;  // sensor messages delivered since the run began, this tick's
                                 // included (the estimator counters' bound)
  int image_width_px = 0;        // the camera image, when frames cross (0: none cross)
  int image_height_px = 0;
};

/// Checks a decoded reply against its tick; throws ProtocolError naming the field and value:
/// frames_detected outside [0, frames delivered], an estimator counter outside [0, messages
/// delivered so far], no estimate when the tick asked for one or with a command, a camera
/// region of negative size or outside the image.
void CheckReply(const FlightOutputs& out, const ReplyBounds& bounds);

/// The hello_ack's content.
struct HelloAck {
  std::string name;              // the stack's name (metrics.json's flight_stack)
  std::string controller;        // what flies, as metrics.json's controller ("": its name)
  double control_rate_hz = 0.0;  // as the stack states it (0: not stated)
  // the stack commands exactly at its control loop's ticks (control_rate_hz on the hello's
  // tick_hz clock, LockstepClock's nearest-tick rounding) and answers no tick flagged no_reply:
  // the simulator then batches the ticks between the replies it needs
  bool batched_ticks = false;
  // the stack answers detect messages (reads each rendered frame at its capture, region first)
  bool detects_at_capture = false;
  // the stack runs the vehicle's rate loop: the simulator runs none and sends it rate_tick
  bool owns_rate_loop = false;
  // the stack reads rendered frames; false: it is sent none and the run renders none (its
  // camera is not flown)
  bool uses_pixels = true;
};

/// Parses a hello_ack; throws ProtocolError naming the field and value for a protocol_version
/// that is not the integer kProtocolVersion, a name or controller that is not a string of at most
/// kMaxNameBytes, a control rate that is not a finite number >= 0, batched_ticks,
/// detects_at_capture, owns_rate_loop or uses_pixels not a bool, batched_ticks without a control
/// rate in (0, tick_hz], or detects_at_capture with uses_pixels false.
HelloAck ParseHelloAck(const std::vector<uint8_t>& body, double tick_hz = 1000.0);

/// The finish_reply's content.
struct FinishReply {
  std::string estimator;  // the stack's estimator ("" with ground truth)
  std::vector<std::pair<std::string, double>> estimator_health;  // its counters, in order
  int frames_detected = 0;  // of the finish's frames, those with the payload
};

/// Longest name (bytes) a stack may give itself, its estimator or a health entry.
constexpr size_t kMaxNameBytes = 128;
/// Most estimator health entries a finish_reply may carry.
constexpr size_t kMaxHealthEntries = 1000;

/// Parses a finish_reply answering a finish that carried `frames` frames; throws ProtocolError
/// naming the field and value for frames_detected that is not an integer in [0, frames], an
/// estimator name that is not a string, or a health entry that is not [name, finite number]
/// with a name of letters, digits and underscores, unique and not a key metrics.json's
/// estimator block reserves (variant).
FinishReply ParseFinishReply(const std::vector<uint8_t>& body, size_t frames);

/// Params as JSON (the hello's config.params): every declared value by its C++ name.
nlohmann::json ParamsToJson(const Params& params);
/// Params from ParamsToJson's JSON, each value checked against its declared range; throws
/// ProtocolError naming SECTION.name for a missing key or a value outside its range.
Params ParamsFromJson(const nlohmann::json& j, const std::string& section = "params");
/// A payload reference spec as JSON (the hello's config.reference); doubles keep every bit.
nlohmann::json ReferenceToJson(const ReferenceSpec& reference);
/// ReferenceToJson's JSON read back; throws ProtocolError for a missing key, a type this side
/// does not have or a key value outside its declared range.
ReferenceSpec ReferenceFromJson(const nlohmann::json& j);

/// FlightConfig as JSON (the hello's "config"); doubles keep every bit.
nlohmann::json ConfigToJson(const FlightConfig& config);
/// FlightConfig from the hello's "config"; throws ProtocolError naming a missing or bad key.
FlightConfig ConfigFromJson(const nlohmann::json& j);

/// How long one message's send or receipt may take: a time limit on the whole message (header
/// and body together, however the peer splits them) and a check, polled every kStopPollS, that
/// ends the wait early.
struct WaitLimit {
  double timeout_s = 0.0;      // the whole message within this (<= 0: no limit)
  std::function<bool()> stop;  // true: stop waiting (WaitInterrupted); empty: never
};

/// How often a wait polls its stop check (s): a stop ends a wait within this.
constexpr double kStopPollS = 0.05;

/// One connected stream socket with message framing and a per-message time limit.
class Channel {
 public:
  /// Takes ownership of a connected socket.
  explicit Channel(int fd) : fd_(fd) {}
  ~Channel();
  Channel(const Channel&) = delete;
  Channel& operator=(const Channel&) = delete;

  /// Sends one message within `limit` (with the messages queued before it); throws
  /// ProtocolError if the peer has gone or reads nothing until the limit, WaitInterrupted when
  /// the limit's stop check ends the wait.
  void Send(MessageType type, const std::vector<uint8_t>& body, const WaitLimit& limit = {});
  /// Queues one message, sent with the next Send or Flush (several messages, one write).
  void Queue(MessageType type, const std::vector<uint8_t>& body);
  /// Sends the queued messages within `limit` (as Send).
  void Flush(const WaitLimit& limit = {});
  /// Sends a JSON message within `limit`, checked first against the table's keys
  /// (CheckJsonMessage: a message this side builds wrongly is refused before it goes).
  void SendJson(MessageType type, const nlohmann::json& j, const WaitLimit& limit = {});
  /// Receives one whole message within `limit` (read ahead in large reads: the messages already
  /// arrived take no system call); throws ProtocolError on a timeout, a closed
  /// peer, a bad magic or an oversized length, WaitInterrupted when the stop check ends the
  /// wait. A kError message is thrown as its text (invalid UTF-8 replaced).
  MessageType Receive(std::vector<uint8_t>* body, const WaitLimit& limit);
  /// Receive within timeout_s (<= 0: no limit), no stop check.
  MessageType Receive(std::vector<uint8_t>* body, double timeout_s);
  /// Receives a message that must be of `type` (ProtocolError naming both otherwise).
  std::vector<uint8_t> Expect(MessageType type, const WaitLimit& limit);
  /// Expect within timeout_s (<= 0: no limit), no stop check.
  std::vector<uint8_t> Expect(MessageType type, double timeout_s);
  /// Whether bytes from the peer wait unread (read ahead, or on the socket), without waiting:
  /// in lockstep, a peer that was asked nothing has nothing to say (a second reply).
  bool HasUnread();
  /// The socket (owned).
  int fd() const { return fd_; }

 private:
  // Reads n bytes into data within `wait` (const MessageWait*, opaque here); false on its
  // deadline; `got` counts what arrived.
  bool ReadExact(uint8_t* data, size_t n, const void* wait, size_t* got);

  int fd_;
  std::vector<uint8_t> out_;         // queued messages, framed, not yet sent
  MessageType out_last_type_ = MessageType::kTick;  // the last one queued (named by errors)
  std::vector<uint8_t> in_;          // bytes read ahead
  size_t in_begin_ = 0, in_end_ = 0;  // the unread bytes of in_
};

/// Connects to the simulator's socket at `path`; throws ProtocolError if it cannot.
int ConnectUnix(const std::string& path);

}  // namespace hpa::flight
