// What every message of the lockstep protocol uses: the message types' names and the cleaning of
// a peer's text (protocol.h), and what the single vehicle's messages and a team's share
// (protocol_common.h): the codecs of the structs both carry, and the reading of a JSON message
// (its object, its protocol_version, its name keys) with the text each refusal shows. Each
// message family's codecs are in a file of their own (tick_messages.cc, detect_messages.cc,
// rate_messages.cc, json_messages.cc, team_protocol.cc), the socket in channel.cc.

#include "hpa/flight/protocol.h"

#include <algorithm>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "message_codecs.h"
#include "message_table.h"
#include "protocol_common.h"

namespace hpa::flight {

using wire::Bind;

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

}  // namespace hpa::flight
