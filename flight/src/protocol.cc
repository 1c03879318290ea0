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

#include "hpa/flight/team_protocol.h"
#include "message_table.h"
#include "protocol_common.h"

namespace hpa::flight {
namespace {

using wire::Bind;
using wire::BindBit;
using wire::Codec;

// Each struct that crosses the wire, bound member by member to its struct of the message table
// (python/hpa_sim/messages.json): the table declares the fields' order, types, units and checks,
// these bindings say which member holds each.

const Codec<SystemState>& StateCodec() {
  static const Codec<SystemState> codec(
      "state", {Bind("time_s", &SystemState::time_s), Bind("p_WL_W", &SystemState::p_WL_W),
                Bind("v_WL_W", &SystemState::v_WL_W), Bind("p_WQ_W", &SystemState::p_WQ_W),
                Bind("v_WQ_W", &SystemState::v_WQ_W), Bind("q_WB", &SystemState::q_WB),
                Bind("w_B", &SystemState::w_B), Bind("mode", &SystemState::mode),
                BindBit("payload_visible", &SystemState::payload_visible),
                BindBit("payload_lost", &SystemState::payload_lost),
                BindBit("payload_supported", &SystemState::payload_supported)});
  return codec;
}

const Codec<ReferenceSample>& ReferenceCodec() {
  static const Codec<ReferenceSample> codec(
      "reference_sample",
      {Bind("p_WL_W", &ReferenceSample::p_WL_W), Bind("v_WL_W", &ReferenceSample::v_WL_W),
       Bind("a_WL_W", &ReferenceSample::a_WL_W)});
  return codec;
}

const Codec<AllocationReport>& AllocationCodec() {
  static const Codec<AllocationReport> codec(
      "allocation_report", {Bind("thrust_allocated_N", &AllocationReport::thrust_allocated_N)});
  return codec;
}

const Codec<EstimatorHealthResets>& HealthResetsCodec() {
  static const Codec<EstimatorHealthResets> codec(
      "health_resets", {Bind("quad_non_finite", &EstimatorHealthResets::quad_non_finite),
                        Bind("payload_non_finite", &EstimatorHealthResets::payload_non_finite),
                        Bind("payload_speed", &EstimatorHealthResets::payload_speed),
                        Bind("cable_length", &EstimatorHealthResets::cable_length)});
  return codec;
}

const Codec<ImuSample>& ImuCodec() {
  static const Codec<ImuSample> codec(
      "imu_sample",
      {Bind("time_s", &ImuSample::time_s), Bind("gyro_B_radps", &ImuSample::gyro_B_radps),
       Bind("accel_B_mps2", &ImuSample::accel_B_mps2)});
  return codec;
}

const Codec<VioSample>& VioCodec() {
  static const Codec<VioSample> codec(
      "vio_sample", {Bind("time_s", &VioSample::time_s), Bind("p_WB_W", &VioSample::p_WB_W),
                     Bind("q_WB", &VioSample::q_WB), Bind("v_WB_W", &VioSample::v_WB_W)});
  return codec;
}

const Codec<PayloadDetection>& DetectionCodec() {
  static const Codec<PayloadDetection> codec(
      "payload_detection",
      {Bind("time_s", &PayloadDetection::time_s), Bind("found", &PayloadDetection::found),
       Bind("p_CL_C", &PayloadDetection::p_CL_C), Bind("centre_px", &PayloadDetection::centre_px),
       Bind("radius_px", &PayloadDetection::radius_px), Bind("reason", &PayloadDetection::reason)});
  return codec;
}

const Codec<CameraFrame>& FrameCodec() {
  static const Codec<CameraFrame> codec(
      "camera_frame",
      {Bind("capture_time_s", &CameraFrame::capture_time_s), Bind("region", &CameraFrame::region),
       Bind("region_slot", &CameraFrame::region_slot),
       Bind("whole_slot", &CameraFrame::whole_slot)});
  return codec;
}

const Codec<FlightInputs>& TickCodec() {
  static const Codec<FlightInputs> codec(
      "tick",
      {Bind("time_s", &FlightInputs::time_s),
       // the mixer's saturation travels as a flag beside the allocation it belongs to
       BindBit<FlightInputs>(
           "saturated",
           [](const FlightInputs& in) { return in.allocation && in.allocation->saturated; },
           [](FlightInputs& in, bool v) {
             if (in.allocation) in.allocation->saturated = v;
           }),
       BindBit("need_estimate", &FlightInputs::need_estimate),
       BindBit("gripper_active", &FlightInputs::gripper_active),
       BindBit("no_reply", &FlightInputs::no_reply),
       Bind("allocation", &FlightInputs::allocation, AllocationCodec()),
       Bind("reference", &FlightInputs::reference, ReferenceCodec()),
       Bind("imu", &FlightInputs::imu, ImuCodec()), Bind("vio", &FlightInputs::vio, VioCodec()),
       Bind("detections", &FlightInputs::detections, DetectionCodec()),
       Bind("frames", &FlightInputs::frames, FrameCodec()),
       Bind("truth", &FlightInputs::truth, StateCodec())});
  return codec;
}

const Codec<FlightOutputs>& ReplyCodec() {
  static const Codec<FlightOutputs> codec(
      "tick_reply",
      {Bind("command", &FlightOutputs::command, ControlOutputCodec(), &FlightOutputs::has_command),
       Bind("estimate", &FlightOutputs::estimate, StateCodec(), &FlightOutputs::has_estimate),
       Bind("rejected_updates", &FlightOutputs::estimator_rejected_updates),
       Bind("resets", &FlightOutputs::estimator_resets),
       Bind("frames_detected", &FlightOutputs::frames_detected),
       Bind("camera_roi", &FlightOutputs::camera_roi),
       Bind("health_resets", &FlightOutputs::estimator_health_resets, HealthResetsCodec())});
  return codec;
}

const Codec<DetectReply>& DetectReplyCodec() {
  static const Codec<DetectReply> codec(
      "detect_reply",
      {BindBit("region_wanted", &DetectReply::region_wanted),
       BindBit("whole_wanted", &DetectReply::whole_wanted),
       Bind("camera_roi", &DetectReply::camera_roi),
       Bind("detection", &DetectReply::detection, DetectionCodec(), &DetectReply::has_detection)});
  return codec;
}

const Codec<RateTick>& RateTickCodec() {
  static const Codec<RateTick> codec("rate_tick",
                                     {Bind("time_s", &RateTick::time_s),
                                      Bind("command", &RateTick::command, BodyRateCommandCodec()),
                                      Bind("w_B_radps", &RateTick::w_B_radps)});
  return codec;
}

const Codec<AutopilotOutput>& RateReplyCodec() {
  static const Codec<AutopilotOutput> codec(
      "rate_reply", {Bind("w_cmd_radps", &AutopilotOutput::w_cmd_radps),
                     Bind("thrust_allocated_N", &AutopilotOutput::thrust_allocated_N),
                     Bind("saturated", &AutopilotOutput::saturated)});
  return codec;
}

// Whether `name` is 1 to kMaxNameBytes letters, digits and underscores.
bool IsIdentifier(const std::string& name) {
  if (name.empty() || name.size() > kMaxNameBytes) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
  });
}

// A message's JSON object; ProtocolError naming the message when it is not one.
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

}  // namespace

// ---- shared with the team's messages (protocol_common.h) ----------------------------------

const wire::Codec<BodyRateCommand>& BodyRateCommandCodec() {
  static const wire::Codec<BodyRateCommand> codec("body_rate_command",
                                                  {Bind("w_B_radps", &BodyRateCommand::w_B_radps),
                                                   Bind("thrust_N", &BodyRateCommand::thrust_N)});
  return codec;
}

const wire::Codec<ControlOutput>& ControlOutputCodec() {
  static const wire::Codec<ControlOutput> codec(
      "control_output",
      {Bind("command", &ControlOutput::command, BodyRateCommandCodec()),
       Bind("status", &ControlOutput::status), Bind("solve_time_ms", &ControlOutput::solve_time_ms),
       Bind("cost", &ControlOutput::cost)});
  return codec;
}

std::string Shown(const nlohmann::json& j) {
  std::string text = j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  if (text.size() > 60) text = text.substr(0, 60) + "...";
  return CleanUtf8(text);
}

nlohmann::json ParseVersionedMessage(const std::vector<uint8_t>& body, MessageType type,
                                     const std::string& this_side) {
  const std::string what = MessageTypeName(type);
  const nlohmann::json j = ParseObject(body, what);
  const nlohmann::json version = j.value("protocol_version", nlohmann::json());
  if (!version.is_number_integer() || version.get<int64_t>() < 0 ||
      version.get<uint64_t>() != kProtocolVersion) {
    throw ProtocolError("it speaks protocol version " + Shown(version) + ", " + this_side +
                        " version " + std::to_string(kProtocolVersion) + " (" + what +
                        "'s protocol_version must be the integer " +
                        std::to_string(kProtocolVersion) + ")");
  }
  CheckJsonMessage(type, j);
  return j;
}

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
    case MessageType::kDetect:
      return "detect";
    case MessageType::kDetectReply:
      return "detect_reply";
    case MessageType::kRateTick:
      return "rate_tick";
    case MessageType::kRateReply:
      return "rate_reply";
    case MessageType::kTeamHello:
      return "team_hello";
    case MessageType::kTeamHelloAck:
      return "team_hello_ack";
    case MessageType::kTeamTick:
      return "team_tick";
    case MessageType::kTeamTickReply:
      return "team_tick_reply";
  }
  return "unknown type " + std::to_string(static_cast<uint32_t>(type));
}

namespace {

// A message body encoded by its codec.
template <class T>
std::vector<uint8_t> EncodeBody(const Codec<T>& codec, const T& value) {
  wire::Writer w;
  codec.Encode(value, w);
  return std::move(w.bytes);
}

// A message body `name` decoded by its codec, every byte of it read.
template <class T>
T DecodeBody(const Codec<T>& codec, const std::vector<uint8_t>& body, const char* name) {
  wire::Reader r(body, name);
  T value;
  codec.Decode(r, value, "");
  r.End();
  return value;
}

}  // namespace

std::vector<uint8_t> EncodeTick(const FlightInputs& in) { return EncodeBody(TickCodec(), in); }

FlightInputs DecodeTick(const std::vector<uint8_t>& body) {
  return DecodeBody(TickCodec(), body, "tick");
}

std::vector<uint8_t> EncodeReply(const FlightOutputs& out) {
  return EncodeBody(ReplyCodec(), out);
}

FlightOutputs DecodeReply(const std::vector<uint8_t>& body) {
  return DecodeBody(ReplyCodec(), body, "tick_reply");
}

std::vector<uint8_t> EncodeDetect(const CameraFrame& frame) {
  return EncodeBody(FrameCodec(), frame);
}

CameraFrame DecodeDetect(const std::vector<uint8_t>& body) {
  return DecodeBody(FrameCodec(), body, "detect");
}

std::vector<uint8_t> EncodeDetectReply(const DetectReply& reply) {
  return EncodeBody(DetectReplyCodec(), reply);
}

DetectReply DecodeDetectReply(const std::vector<uint8_t>& body) {
  const DetectReply reply = DecodeBody(DetectReplyCodec(), body, "detect_reply");
  const int set = (reply.has_detection ? 1 : 0) + (reply.region_wanted ? 1 : 0) +
                  (reply.whole_wanted ? 1 : 0);
  if (set != 1) {
    throw ProtocolError("detect_reply refused: " + std::to_string(set) +
                        " of its flags set (detection, region wanted, whole frame wanted), "
                        "expected exactly one");
  }
  return reply;
}

std::vector<uint8_t> EncodeRateTick(const RateTick& tick) {
  return EncodeBody(RateTickCodec(), tick);
}

RateTick DecodeRateTick(const std::vector<uint8_t>& body) {
  return DecodeBody(RateTickCodec(), body, "rate_tick");
}

std::vector<uint8_t> EncodeRateReply(const AutopilotOutput& out) {
  return EncodeBody(RateReplyCodec(), out);
}

AutopilotOutput DecodeRateReply(const std::vector<uint8_t>& body) {
  return DecodeBody(RateReplyCodec(), body, "rate_reply");
}

void CheckRateReply(const AutopilotOutput& out, const Params& params) {
  for (int i = 0; i < out.w_cmd_radps.size(); ++i) {
    const double w_radps = out.w_cmd_radps[i];
    if (w_radps >= params.motor_speed_min_radps && w_radps <= params.motor_speed_max_radps) {
      continue;
    }
    throw ProtocolError("rate_reply refused: rotor " + std::to_string(i) + " speed command " +
                        wire::ShownValue(w_radps) + " rad/s, outside the motors' range [" +
                        wire::ShownLimit(params.motor_speed_min_radps) + ", " +
                        wire::ShownLimit(params.motor_speed_max_radps) + "] rad/s");
  }
}

namespace {

// Whether `v` is of the table's JSON type `type` (integer, number, string, bool, object, array).
bool IsJsonType(const nlohmann::json& v, const std::string& type) {
  if (type == "integer") return v.is_number_integer();
  if (type == "number") return v.is_number();
  if (type == "string") return v.is_string();
  if (type == "bool") return v.is_boolean();
  if (type == "object") return v.is_object();
  if (type == "array") return v.is_array();
  return false;
}

// Checks `j` against `keys` (the table's declarations of one object's keys); `where` names it.
void CheckJsonKeys(const nlohmann::json& keys, const nlohmann::json& j, const std::string& where) {
  if (!j.is_object()) throw ProtocolError(where + " is " + Shown(j) + ", expected a JSON object");
  for (const auto& item : j.items()) {
    const auto declared = std::find_if(keys.begin(), keys.end(), [&](const nlohmann::json& k) {
      return k.at("name") == item.key();
    });
    if (declared == keys.end()) {
      throw ProtocolError(where + "'s key '" + item.key() +
                          "' is not declared in the message table (messages.json)");
    }
    const std::string& type = declared->at("type").get_ref<const std::string&>();
    if (!IsJsonType(item.value(), type)) {
      throw ProtocolError(where + "'s " + item.key() + " is " + Shown(item.value()) +
                          ", expected " + (type == "integer" ? "an " : "a ") + type);
    }
    if (declared->contains("keys")) {
      CheckJsonKeys(declared->at("keys"), item.value(), where + "'s " + item.key());
    }
  }
  for (const nlohmann::json& k : keys) {
    if (k.value("required", false) && !j.contains(k.at("name").get<std::string>())) {
      throw ProtocolError(where + " has no " + k.at("name").get<std::string>());
    }
  }
}

}  // namespace

void CheckJsonMessage(MessageType type, const nlohmann::json& j) {
  for (const nlohmann::json& t : MessageTable().at("message_types")) {
    if (t.at("id") != static_cast<uint32_t>(type)) continue;
    if (!t.contains("keys")) {
      throw ProtocolError(MessageTypeName(type) + " is not a JSON message of the table");
    }
    CheckJsonKeys(t.at("keys"), j, MessageTypeName(type));
    return;
  }
  throw ProtocolError("message type " + std::to_string(static_cast<uint32_t>(type)) +
                      " is not in the message table");
}

const nlohmann::json& MessageTable() { return wire::Table::Get().json(); }

void CheckMessageBindings() {
  TickCodec();
  ReplyCodec();
  DetectReplyCodec();
  RateTickCodec();
  RateReplyCodec();
  CheckTeamMessageBindings();
  // every struct of the table is bound, through the tick's or the reply's codec (a team
  // message's, team_protocol.cc's)
  std::set<std::string> bound;
  const auto visit = [&](const auto& self, const wire::Struct& s) -> void {
    bound.insert(s.name);
    for (const wire::Field& f : s.fields) {
      if (f.type != nullptr) self(self, *f.type);
    }
  };
  visit(visit, TickCodec().spec());
  visit(visit, ReplyCodec().spec());
  visit(visit, DetectReplyCodec().spec());
  visit(visit, RateTickCodec().spec());
  visit(visit, RateReplyCodec().spec());
  for (const char* team : {"team_tick", "team_tick_reply"}) {
    visit(visit, wire::Table::Get().Find(team));
  }
  for (const auto& item : MessageTable().at("structs").items()) {
    if (bound.count(item.key()) == 0) {
      throw std::logic_error("messages.json's struct " + item.key() + " is in no message");
    }
  }
}

void CheckReply(const FlightOutputs& out, const ReplyBounds& bounds) {
  const auto fail = [](const std::string& what) {
    throw ProtocolError("tick_reply refused: " + what);
  };
  if (static_cast<size_t>(out.frames_detected) > bounds.frames) {
    fail("frames_detected " + std::to_string(out.frames_detected) + ", but the tick delivered " +
         std::to_string(bounds.frames) + " frame(s)");
  }
  // each counted update, and each health-check re-initialisation (made at an update), was made
  // with a message the stack received
  std::vector<std::pair<std::string, int>> counts = {
      {"rejected_updates", out.estimator_rejected_updates}, {"resets", out.estimator_resets}};
  if (out.estimator_health_resets) {
    const EstimatorHealthResets& r = *out.estimator_health_resets;
    counts.insert(counts.end(), {{"health_resets.quad_non_finite", r.quad_non_finite},
                                 {"health_resets.payload_non_finite", r.payload_non_finite},
                                 {"health_resets.payload_speed", r.payload_speed},
                                 {"health_resets.cable_length", r.cable_length}});
  }
  for (const auto& [name, v] : counts) {
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

HelloAck ParseHelloAck(const std::vector<uint8_t>& body, double tick_hz) {
  const std::string what = "hello_ack";
  // the version, the keys and their types as the message table declares them; then what the
  // table cannot say
  const nlohmann::json j = ParseVersionedMessage(body, MessageType::kHelloAck, "this simulator");
  HelloAck ack;
  ack.name = NameField(j, what, "name", "external");
  ack.controller = NameField(j, what, "controller", "");
  if (j.contains("control_rate_hz")) {
    const double rate_hz = j.at("control_rate_hz").get<double>();
    if (!std::isfinite(rate_hz) || rate_hz < 0.0) {
      throw ProtocolError("hello_ack's control_rate_hz is " + Shown(j.at("control_rate_hz")) +
                          ", expected a finite number >= 0 (Hz)");
    }
    ack.control_rate_hz = rate_hz;
  }
  ack.batched_ticks = j.value("batched_ticks", false);
  ack.detects_at_capture = j.value("detects_at_capture", false);
  ack.owns_rate_loop = j.value("owns_rate_loop", false);
  if (ack.batched_ticks && !(ack.control_rate_hz > 0.0 && ack.control_rate_hz <= tick_hz)) {
    throw ProtocolError("hello_ack's batched_ticks needs the control rate its ticks follow: "
                        "control_rate_hz is " + Shown(j.value("control_rate_hz", nlohmann::json())) +
                        ", expected a rate in (0, " + Shown(std::lround(tick_hz)) + "] Hz");
  }
  return ack;
}

FinishReply ParseFinishReply(const std::vector<uint8_t>& body, size_t frames) {
  const std::string what = "finish_reply";
  const nlohmann::json j = ParseObject(body, what);
  // the keys and their types as the message table declares them; then what the table cannot say
  CheckJsonMessage(MessageType::kFinishReply, j);
  FinishReply reply;
  reply.estimator = NameField(j, what, "estimator", "");
  if (j.contains("frames_detected")) {
    const nlohmann::json& found = j.at("frames_detected");
    if (found.get<int64_t>() < 0 || found.get<uint64_t>() > frames) {
      throw ProtocolError("finish_reply's frames_detected is " + Shown(found) +
                          ", expected an integer in [0, " + std::to_string(frames) +
                          "] (the frames the finish carried)");
    }
    reply.frames_detected = found.get<int>();
  }
  const nlohmann::json health = j.value("estimator_health", nlohmann::json::array());
  if (health.size() > kMaxHealthEntries) {
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

// Bytes a read asks for at most: many small messages arrive in one read.
constexpr size_t kReadAheadBytes = 64 * 1024;

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
      throw ProtocolError("the peer closed the connection while a " + what + " was sent (" +
                          why + ")");
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
  if (!ReadExact(body->data(), body->size(), &wait, &got))
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
