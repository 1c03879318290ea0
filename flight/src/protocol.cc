#include "hpa/flight/protocol.h"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>

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

}  // namespace

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
  }
  if (out.has_estimate) {
    out.estimate = r.State();
    if (!Finite(out.estimate)) r.Fail("a non-finite estimate");
  }
  out.estimator_rejected_updates = static_cast<int>(r.U32());
  out.estimator_resets = static_cast<int>(r.U32());
  out.frames_detected = static_cast<int>(r.U32());
  out.camera_roi = r.Rect();
  r.End();
  return out;
}

// ---- the socket ---------------------------------------------------------------------------

Channel::~Channel() {
  if (fd_ >= 0) ::close(fd_);
}

void Channel::Send(MessageType type, const std::vector<uint8_t>& body) {
  uint32_t header[3] = {kMagic, static_cast<uint32_t>(type), static_cast<uint32_t>(body.size())};
  const auto write_all = [&](const void* data, size_t n) {
    const auto* p = static_cast<const uint8_t*>(data);
    while (n > 0) {
      const ssize_t k = ::send(fd_, p, n, MSG_NOSIGNAL);
      if (k < 0 && errno == EINTR) continue;
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

void Channel::SendJson(MessageType type, const nlohmann::json& j) {
  const std::string text = j.dump();
  Send(type, std::vector<uint8_t>(text.begin(), text.end()));
}

void Channel::ReadExact(uint8_t* data, size_t n, double timeout_s) {
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  while (n > 0) {
    if (timeout_s > 0) {
      const double left_ms =
          std::chrono::duration<double, std::milli>(deadline - Clock::now()).count();
      pollfd pfd{fd_, POLLIN, 0};
      const int ready = left_ms > 0 ? ::poll(&pfd, 1, static_cast<int>(std::ceil(left_ms))) : 0;
      if (ready < 0 && errno == EINTR) continue;
      if (ready == 0) {
        throw ProtocolError("no answer within " + std::to_string(timeout_s) + " s");
      }
    }
    const ssize_t k = ::recv(fd_, data, n, 0);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) throw ProtocolError("the peer closed the connection");
    data += k;
    n -= static_cast<size_t>(k);
  }
}

MessageType Channel::Receive(std::vector<uint8_t>* body, double timeout_s) {
  uint32_t header[3];
  ReadExact(reinterpret_cast<uint8_t*>(header), sizeof header, timeout_s);
  if (header[0] != kMagic) {
    throw ProtocolError("a message without the protocol's magic (not an hpa lockstep peer?)");
  }
  if (header[2] > kMaxMessageBytes) {
    throw ProtocolError("a message of " + std::to_string(header[2]) + " bytes (at most " +
                        std::to_string(kMaxMessageBytes) + ")");
  }
  body->resize(header[2]);
  ReadExact(body->data(), body->size(), timeout_s);
  const auto type = static_cast<MessageType>(header[1]);
  if (type == MessageType::kError) {
    throw ProtocolError("the peer reported: " + std::string(body->begin(), body->end()));
  }
  return type;
}

std::vector<uint8_t> Channel::Expect(MessageType type, double timeout_s) {
  std::vector<uint8_t> body;
  const MessageType got = Receive(&body, timeout_s);
  if (got != type) {
    throw ProtocolError("expected a " + MessageTypeName(type) + " message, got " +
                        MessageTypeName(got));
  }
  return body;
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
