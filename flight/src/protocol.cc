#include "hpa/flight/protocol.h"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <optional>
#include <set>

namespace hpa::flight {
namespace {

static_assert(sizeof(double) == 8, "the protocol's numbers are IEEE doubles");

// Appends little-endian numbers (this machine's order: x86-64 and arm64 are little-endian).
class Writer {
 public:
  void F64(double v) { Raw(&v, 8); }
  void U32(uint32_t v) { Raw(&v, 4); }
  void Vec(const Eigen::Vector3d& v) {
    for (int i = 0; i < 3; ++i) F64(v[i]);
  }
  void Quat(const Eigen::Quaterniond& q) { F64(q.w()), F64(q.x()), F64(q.y()), F64(q.z()); }
  void Rect(const cv::Rect& r) {
    for (const int v : {r.x, r.y, r.width, r.height}) U32(static_cast<uint32_t>(v));
  }
  void Str(const std::string& s) {
    U32(static_cast<uint32_t>(s.size()));
    Raw(s.data(), s.size());
  }
  void State(const SystemState& s) {
    F64(s.time_s), Vec(s.p_WL_W), Vec(s.v_WL_W), Vec(s.p_WQ_W), Vec(s.v_WQ_W), Quat(s.q_WB);
    Vec(s.w_B);
    U32(s.mode == CableMode::kTaut ? 1 : 0);
    U32((s.payload_visible ? 1u : 0u) | (s.payload_lost ? 2u : 0u) |
        (s.payload_supported ? 4u : 0u));
  }
  std::vector<uint8_t> bytes;

 private:
  void Raw(const void* p, size_t n) {
    const auto* b = static_cast<const uint8_t*>(p);
    bytes.insert(bytes.end(), b, b + n);
  }
};

// Reads what Writer wrote; every read is bounds-checked.
class Reader {
 public:
  Reader(const std::vector<uint8_t>& bytes, const char* what) : bytes_(bytes), what_(what) {}
  double F64() {
    double v;
    Raw(&v, 8);
    return v;
  }
  uint32_t U32() {
    uint32_t v;
    Raw(&v, 4);
    return v;
  }
  Eigen::Vector3d Vec() {
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) v[i] = F64();
    return v;
  }
  Eigen::Quaterniond Quat() {
    const double w = F64(), x = F64(), y = F64(), z = F64();
    return Eigen::Quaterniond(w, x, y, z);
  }
  cv::Rect Rect() {
    const int x = static_cast<int32_t>(U32()), y = static_cast<int32_t>(U32());
    const int w = static_cast<int32_t>(U32()), h = static_cast<int32_t>(U32());
    return cv::Rect(x, y, w, h);
  }
  std::string Str() {
    const uint32_t n = U32();
    if (n > bytes_.size() - pos_) Fail("a string longer than the message");
    std::string s(reinterpret_cast<const char*>(bytes_.data() + pos_), n);
    pos_ += n;
    return s;
  }
  // a count of items of at least item_bytes each (refused when the message cannot hold them)
  uint32_t Count(size_t item_bytes) {
    const uint32_t n = U32();
    if (static_cast<size_t>(n) * item_bytes > bytes_.size() - pos_) Fail("a count beyond its end");
    return n;
  }
  SystemState State() {
    SystemState s;
    s.time_s = F64();
    s.p_WL_W = Vec(), s.v_WL_W = Vec(), s.p_WQ_W = Vec(), s.v_WQ_W = Vec();
    s.q_WB = Quat();
    s.w_B = Vec();
    const uint32_t mode = U32();
    if (mode > 1) Fail("cable mode " + std::to_string(mode) + " (0 slack, 1 taut)");
    s.mode = mode == 1 ? CableMode::kTaut : CableMode::kSlack;
    const uint32_t flags = U32();
    if ((flags & ~7u) != 0) {
      Fail("state flags " + std::to_string(flags) +
           " with unknown bits (1 payload visible, 2 payload lost, 4 payload supported)");
    }
    s.payload_visible = (flags & 1u) != 0;
    s.payload_lost = (flags & 2u) != 0;
    s.payload_supported = (flags & 4u) != 0;
    return s;
  }
  void End() {
    if (pos_ != bytes_.size()) {
      Fail(std::to_string(bytes_.size() - pos_) + " bytes after its end");
    }
  }
  [[noreturn]] void Fail(const std::string& what) const {
    throw ProtocolError(std::string("malformed ") + what_ + " message: " + what);
  }

 private:
  void Raw(void* p, size_t n) {
    if (n > bytes_.size() - pos_) Fail("it ends early");
    std::memcpy(p, bytes_.data() + pos_, n);
    pos_ += n;
  }
  const std::vector<uint8_t>& bytes_;
  const char* what_;
  size_t pos_ = 0;
};

constexpr uint32_t kHasAllocation = 1u, kSaturated = 2u, kHasTruth = 4u, kNeedEstimate = 8u,
                   kGripperActive = 16u;
constexpr uint32_t kHasCommand = 1u, kHasEstimate = 2u;

bool Finite(const SystemState& s) { return s.AllFinite() && std::isfinite(s.time_s); }

// A number as an error message shows it: every digit that tells it apart.
std::string Shown(double v) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

// A JSON value as an error message shows it: its text, cut after 60 bytes.
std::string Shown(const nlohmann::json& j) {
  std::string text = j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  if (text.size() > 60) text = text.substr(0, 60) + "...";
  return CleanUtf8(text);
}

// Whether `name` is 1 to kMaxNameBytes letters, digits and underscores.
bool IsIdentifier(const std::string& name) {
  if (name.empty() || name.size() > kMaxNameBytes) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
  });
}

// A reply's JSON object; ProtocolError naming the message when it is not one.
nlohmann::json ParseObject(const std::vector<uint8_t>& body, const std::string& what) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(body.begin(), body.end());
  } catch (const nlohmann::json::exception& e) {
    throw ProtocolError("a malformed " + what + ": " + e.what());
  }
  if (!j.is_object()) throw ProtocolError(what + " is " + Shown(j) + ", expected a JSON object");
  return j;
}

// An optional string field of a reply (absent: `fallback`), at most kMaxNameBytes long.
std::string NameField(const nlohmann::json& j, const std::string& what, const char* key,
                      const std::string& fallback) {
  if (!j.contains(key)) return fallback;
  const nlohmann::json& v = j.at(key);
  if (!v.is_string() || v.get_ref<const std::string&>().size() > kMaxNameBytes) {
    throw ProtocolError(what + "'s " + key + " is " + Shown(v) + ", expected a string of at most " +
                        std::to_string(kMaxNameBytes) + " bytes");
  }
  return CleanUtf8(v.get<std::string>());
}

}  // namespace

std::string CleanUtf8(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  const auto byte = [&](size_t i) { return static_cast<unsigned char>(text[i]); };
  size_t i = 0;
  while (i < text.size()) {
    const unsigned char c = byte(i);
    // the sequence's length and the range its second byte must fall in (RFC 3629: no overlong
    // forms, no surrogates, nothing past U+10FFFF)
    size_t n = 0;
    unsigned char lo = 0x80, hi = 0xBF;
    if (c < 0x80) {
      n = 1;
    } else if (c >= 0xC2 && c <= 0xDF) {
      n = 2;
    } else if (c >= 0xE0 && c <= 0xEF) {
      n = 3;
      if (c == 0xE0) lo = 0xA0;
      if (c == 0xED) hi = 0x9F;
    } else if (c >= 0xF0 && c <= 0xF4) {
      n = 4;
      if (c == 0xF0) lo = 0x90;
      if (c == 0xF4) hi = 0x8F;
    }
    size_t valid = n == 0 ? 0 : 1;  // bytes of the sequence that are well formed so far
    while (valid > 0 && valid < n && i + valid < text.size()) {
      const unsigned char b = byte(i + valid);
      if (b < (valid == 1 ? lo : 0x80) || b > (valid == 1 ? hi : 0xBF)) break;
      ++valid;
    }
    if (n > 0 && valid == n) {
      out.append(text.substr(i, n));
      i += n;
    } else {
      out += "\xEF\xBF\xBD";  // U+FFFD for the ill-formed part, then go on after it
      i += std::max<size_t>(valid, 1);
    }
  }
  return out;
}

std::string MessageTypeName(MessageType type) {
  switch (type) {
    case MessageType::kHello:
      return "hello";
    case MessageType::kHelloAck:
      return "hello_ack";
    case MessageType::kTick:
      return "tick";
    case MessageType::kTickReply:
      return "tick_reply";
    case MessageType::kFinish:
      return "finish";
    case MessageType::kFinishReply:
      return "finish_reply";
    case MessageType::kError:
      return "error";
  }
  return "unknown type " + std::to_string(static_cast<uint32_t>(type));
}

std::vector<uint8_t> EncodeTick(const FlightInputs& in) {
  Writer w;
  w.F64(in.time_s);
  uint32_t flags = 0;
  if (in.allocation) flags |= kHasAllocation | (in.allocation->saturated ? kSaturated : 0u);
  if (in.truth) flags |= kHasTruth;
  if (in.need_estimate) flags |= kNeedEstimate;
  if (in.gripper_active) flags |= kGripperActive;
  w.U32(flags);
  if (in.allocation) w.F64(in.allocation->thrust_allocated_N);
  w.Vec(in.reference.p_WL_W), w.Vec(in.reference.v_WL_W), w.Vec(in.reference.a_WL_W);
  w.U32(static_cast<uint32_t>(in.imu.size()));
  for (const ImuSample& s : in.imu) w.F64(s.time_s), w.Vec(s.gyro_B_radps), w.Vec(s.accel_B_mps2);
  w.U32(static_cast<uint32_t>(in.vio.size()));
  for (const VioSample& s : in.vio)
    w.F64(s.time_s), w.Vec(s.p_WB_W), w.Quat(s.q_WB), w.Vec(s.v_WB_W);
  w.U32(static_cast<uint32_t>(in.detections.size()));
  for (const PayloadDetection& d : in.detections) {
    w.F64(d.time_s), w.U32(d.found ? 1 : 0), w.Vec(d.p_CL_C);
    w.F64(d.centre_px.x()), w.F64(d.centre_px.y()), w.F64(d.radius_px), w.Str(d.reason);
  }
  w.U32(static_cast<uint32_t>(in.frames.size()));
  for (const CameraFrame& f : in.frames) {
    w.F64(f.capture_time_s), w.Rect(f.region);
    w.U32(static_cast<uint32_t>(f.region_slot)), w.U32(static_cast<uint32_t>(f.whole_slot));
  }
  if (in.truth) w.State(*in.truth);
  return std::move(w.bytes);
}

FlightInputs DecodeTick(const std::vector<uint8_t>& body) {
  Reader r(body, "tick");
  FlightInputs in;
  in.time_s = r.F64();
  const uint32_t flags = r.U32();
  if (flags & kHasAllocation) {
    in.allocation = AllocationReport{r.F64(), (flags & kSaturated) != 0};
  }
  in.need_estimate = (flags & kNeedEstimate) != 0;
  in.gripper_active = (flags & kGripperActive) != 0;
  in.reference.p_WL_W = r.Vec(), in.reference.v_WL_W = r.Vec(), in.reference.a_WL_W = r.Vec();
  in.imu.resize(r.Count(7 * 8));
  for (ImuSample& s : in.imu)
    s.time_s = r.F64(), s.gyro_B_radps = r.Vec(), s.accel_B_mps2 = r.Vec();
  in.vio.resize(r.Count(11 * 8));
  for (VioSample& s : in.vio)
    s.time_s = r.F64(), s.p_WB_W = r.Vec(), s.q_WB = r.Quat(), s.v_WB_W = r.Vec();
  in.detections.resize(r.Count(7 * 8 + 2 * 4));
  for (PayloadDetection& d : in.detections) {
    d.time_s = r.F64();
    d.found = r.U32() != 0;
    d.p_CL_C = r.Vec();
    d.centre_px.x() = r.F64();
    d.centre_px.y() = r.F64();
    d.radius_px = r.F64();
    d.reason = r.Str();
  }
  in.frames.resize(r.Count(8 + 6 * 4));
  for (CameraFrame& f : in.frames) {
    f.capture_time_s = r.F64();
    f.region = r.Rect();
    f.region_slot = static_cast<int32_t>(r.U32());
    f.whole_slot = static_cast<int32_t>(r.U32());
  }
  if (flags & kHasTruth) in.truth = r.State();
  r.End();
  return in;
}

std::vector<uint8_t> EncodeReply(const FlightOutputs& out) {
  Writer w;
  w.U32((out.has_command ? kHasCommand : 0u) | (out.has_estimate ? kHasEstimate : 0u));
  if (out.has_command) {
    w.Vec(out.command.command.w_B_radps);
    w.F64(out.command.command.thrust_N);
    w.U32(static_cast<uint32_t>(out.command.status));
    w.F64(out.command.solve_time_ms);
    w.F64(out.command.cost);
  }
  if (out.has_estimate) w.State(out.estimate);
  w.U32(static_cast<uint32_t>(out.estimator_rejected_updates));
  w.U32(static_cast<uint32_t>(out.estimator_resets));
  w.U32(static_cast<uint32_t>(out.frames_detected));
  w.Rect(out.camera_roi);
  return std::move(w.bytes);
}

FlightOutputs DecodeReply(const std::vector<uint8_t>& body) {
  Reader r(body, "tick_reply");
  FlightOutputs out;
  const uint32_t flags = r.U32();
  out.has_command = (flags & kHasCommand) != 0;
  out.has_estimate = (flags & kHasEstimate) != 0;
  if (out.has_command) {
    out.command.command.w_B_radps = r.Vec();
    out.command.command.thrust_N = r.F64();
    const uint32_t status = r.U32();
    if (status > static_cast<uint32_t>(ControlStatus::kRecovery)) {
      r.Fail("control status " + std::to_string(status) + " (0 to " +
             std::to_string(static_cast<int>(ControlStatus::kRecovery)) + ")");
    }
    out.command.status = static_cast<ControlStatus>(status);
    out.command.solve_time_ms = r.F64();
    out.command.cost = r.F64();
    if (!out.command.command.w_B_radps.allFinite() ||
        !std::isfinite(out.command.command.thrust_N)) {
      r.Fail("a non-finite command (body rate or thrust)");
    }
    // a wall-clock time, at most the longest wait for a reply
    const double solve_ms = out.command.solve_time_ms;
    if (!(solve_ms >= 0.0 && solve_ms <= kMaxSolveTimeMs)) {
      r.Fail("solve time " + Shown(solve_ms) + " ms, expected a time in [0, " +
             Shown(kMaxSolveTimeMs) + "] ms");
    }
    // a sum of squared residuals (0 for a controller that is not an MPC)
    if (!(std::isfinite(out.command.cost) && out.command.cost >= 0.0)) {
      r.Fail("cost " + Shown(out.command.cost) + ", expected a finite number >= 0");
    }
  }
  if (out.has_estimate) {
    out.estimate = r.State();
    if (!Finite(out.estimate)) r.Fail("a non-finite estimate");
    // an attitude: a unit quaternion; one off by more than rounding is renormalised, one far
    // from unit (zero, or scaled) is not an attitude
    const double norm = out.estimate.q_WB.norm();
    if (!(norm >= 0.9 && norm <= 1.1)) {
      r.Fail("an estimate quaternion q_WB of norm " + Shown(norm) +
             ", expected a unit quaternion (norm in [0.9, 1.1])");
    }
    if (std::fabs(norm - 1.0) > 1e-9) out.estimate.q_WB.normalize();
  }
  const uint32_t rejected = r.U32(), resets = r.U32(), frames = r.U32();
  // counters beyond INT_MAX are refused here, the tighter bounds by CheckReply
  for (const auto& [name, v] : {std::pair<const char*, uint32_t>{"rejected_updates", rejected},
                                {"resets", resets},
                                {"frames_detected", frames}}) {
    if (v > static_cast<uint32_t>(std::numeric_limits<int32_t>::max())) {
      r.Fail(std::string(name) + " " + std::to_string(v) + " (at most 2^31 - 1)");
    }
  }
  out.estimator_rejected_updates = static_cast<int>(rejected);
  out.estimator_resets = static_cast<int>(resets);
  out.frames_detected = static_cast<int>(frames);
  out.camera_roi = r.Rect();
  r.End();
  return out;
}

void CheckReply(const FlightOutputs& out, const ReplyBounds& bounds) {
  const auto fail = [](const std::string& what) {
    throw ProtocolError("tick_reply refused: " + what);
  };
  if (static_cast<size_t>(out.frames_detected) > bounds.frames) {
    fail("frames_detected " + std::to_string(out.frames_detected) + ", but the tick delivered " +
         std::to_string(bounds.frames) + " frame(s)");
  }
  // each counted update was made with a message the stack received
  for (const auto& [name, v] :
       {std::pair<const char*, int>{"rejected_updates", out.estimator_rejected_updates},
        {"resets", out.estimator_resets}}) {
    if (static_cast<uint64_t>(v) > bounds.messages_so_far) {
      fail(std::string(name) + " " + std::to_string(v) + ", more than the " +
           std::to_string(bounds.messages_so_far) + " sensor messages delivered so far");
    }
  }
  if (bounds.estimate_needed && !out.has_estimate) {
    fail("no estimate, but the tick asked for one (flag 8, estimate needed)");
  }
  if (out.has_command && !out.has_estimate) {
    fail("a command without the estimate it was computed from");
  }
  const cv::Rect& roi = out.camera_roi;
  if (roi.width < 0 || roi.height < 0) {
    fail("camera_roi of size " + std::to_string(roi.width) + " x " + std::to_string(roi.height));
  }
  if (bounds.image_width_px > 0 && roi.area() > 0 &&
      (roi.x < 0 || roi.y < 0 || roi.x > bounds.image_width_px - roi.width ||
       roi.y > bounds.image_height_px - roi.height)) {
    fail("camera_roi (" + std::to_string(roi.x) + ", " + std::to_string(roi.y) + ", " +
         std::to_string(roi.width) + ", " + std::to_string(roi.height) + ") outside the " +
         std::to_string(bounds.image_width_px) + " x " + std::to_string(bounds.image_height_px) +
         " image");
  }
}

HelloAck ParseHelloAck(const std::vector<uint8_t>& body) {
  const std::string what = "hello_ack";
  const nlohmann::json j = ParseObject(body, what);
  // the version: exactly the integer this side speaks (1.9 or 2^32 + 1 are not version 1)
  const nlohmann::json version = j.value("protocol_version", nlohmann::json());
  if (!version.is_number_integer() || version.get<int64_t>() < 0 ||
      version.get<uint64_t>() != kProtocolVersion) {
    throw ProtocolError("it speaks protocol version " + Shown(version) +
                        ", this simulator version " + std::to_string(kProtocolVersion) +
                        " (hello_ack's protocol_version must be the integer " +
                        std::to_string(kProtocolVersion) + ")");
  }
  HelloAck ack;
  ack.name = NameField(j, what, "name", "external");
  ack.controller = NameField(j, what, "controller", "");
  if (j.contains("control_rate_hz")) {
    const nlohmann::json& rate = j.at("control_rate_hz");
    if (!rate.is_number() || !std::isfinite(rate.get<double>()) || rate.get<double>() < 0.0) {
      throw ProtocolError("hello_ack's control_rate_hz is " + Shown(rate) +
                          ", expected a finite number >= 0 (Hz)");
    }
    ack.control_rate_hz = rate.get<double>();
  }
  return ack;
}

FinishReply ParseFinishReply(const std::vector<uint8_t>& body, size_t frames) {
  const std::string what = "finish_reply";
  const nlohmann::json j = ParseObject(body, what);
  FinishReply reply;
  reply.estimator = NameField(j, what, "estimator", "");
  if (j.contains("frames_detected")) {
    const nlohmann::json& found = j.at("frames_detected");
    if (!found.is_number_integer() || found.get<int64_t>() < 0 || found.get<uint64_t>() > frames) {
      throw ProtocolError("finish_reply's frames_detected is " + Shown(found) +
                          ", expected an integer in [0, " + std::to_string(frames) +
                          "] (the frames the finish carried)");
    }
    reply.frames_detected = found.get<int>();
  }
  const nlohmann::json health = j.value("estimator_health", nlohmann::json::array());
  if (!health.is_array() || health.size() > kMaxHealthEntries) {
    throw ProtocolError("finish_reply's estimator_health is " + Shown(health) +
                        ", expected a list of at most " + std::to_string(kMaxHealthEntries) +
                        " [name, value] pairs");
  }
  // metrics.json's estimator block holds the variant beside these: its keys are not theirs
  static const std::set<std::string> reserved = {"variant"};
  std::set<std::string> seen;
  for (size_t i = 0; i < health.size(); ++i) {
    const nlohmann::json& kv = health[i];
    const std::string entry = "finish_reply's estimator_health entry " + std::to_string(i);
    if (!kv.is_array() || kv.size() != 2 || !kv[0].is_string() || !kv[1].is_number() ||
        !std::isfinite(kv[1].get<double>())) {
      throw ProtocolError(entry + " is " + Shown(kv) + ", expected [name, finite number]");
    }
    const std::string name = kv[0].get<std::string>();
    if (!IsIdentifier(name)) {
      throw ProtocolError(entry + " is named " + Shown(kv[0]) + ", expected 1 to " +
                          std::to_string(kMaxNameBytes) + " letters, digits or underscores");
    }
    if (reserved.count(name) > 0) {
      throw ProtocolError(entry + " is named '" + name +
                          "', a key metrics.json's estimator block reserves");
    }
    if (!seen.insert(name).second) throw ProtocolError(entry + " repeats the name '" + name + "'");
    reply.estimator_health.emplace_back(name, kv[1].get<double>());
  }
  return reply;
}

// ---- the socket ---------------------------------------------------------------------------

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

// Reads n bytes into data within the wait; false on its deadline. `got` counts what arrived.
bool ReadExact(int fd, uint8_t* data, size_t n, const MessageWait& wait, size_t* got) {
  while (n > 0) {
    if (!wait.Ready(fd, POLLIN)) return false;
    const ssize_t k = ::recv(fd, data, n, MSG_DONTWAIT);
    if (k < 0 && (errno == EINTR || errno == EAGAIN || errno == EWOULDBLOCK)) continue;
    if (k <= 0) throw ProtocolError("the peer closed the connection");
    data += k;
    n -= static_cast<size_t>(k);
    *got += static_cast<size_t>(k);
  }
  return true;
}

}  // namespace

void Channel::Send(MessageType type, const std::vector<uint8_t>& body, const WaitLimit& limit) {
  const MessageWait wait(limit);
  uint32_t header[3] = {kMagic, static_cast<uint32_t>(type), static_cast<uint32_t>(body.size())};
  const auto write_all = [&](const void* data, size_t n) {
    const auto* p = static_cast<const uint8_t*>(data);
    while (n > 0) {
      if (!wait.Ready(fd_, POLLOUT)) {
        throw ProtocolError("the peer took no " + MessageTypeName(type) + " message within " +
                            std::to_string(limit.timeout_s) + " s (it reads nothing)");
      }
      const ssize_t k = ::send(fd_, p, n, MSG_NOSIGNAL | MSG_DONTWAIT);
      if (k < 0 && (errno == EINTR || errno == EAGAIN || errno == EWOULDBLOCK)) continue;
      if (k <= 0) {
        throw ProtocolError("the peer closed the connection while a " + MessageTypeName(type) +
                            " message was sent (" + std::strerror(errno) + ")");
      }
      p += k;
      n -= static_cast<size_t>(k);
    }
  };
  write_all(header, sizeof header);
  write_all(body.data(), body.size());
}

void Channel::SendJson(MessageType type, const nlohmann::json& j, const WaitLimit& limit) {
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
  if (!ReadExact(fd_, reinterpret_cast<uint8_t*>(header), sizeof header, wait, &got)) {
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
  if (!ReadExact(fd_, body->data(), body->size(), wait, &got))
    throw late(sizeof header + header[2]);
  const auto type = static_cast<MessageType>(header[1]);
  if (type == MessageType::kError) {
    // the peer's own words, which may not be UTF-8: they end up in JSON (a run error)
    throw ProtocolError(
        "the peer reported: " +
        CleanUtf8(std::string_view(reinterpret_cast<const char*>(body->data()), body->size())));
  }
  return type;
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
