// The JSON messages of the lockstep protocol (docs/protocol.md): their check against the keys the
// message table declares, and the reading of a hello_ack and of a finish_reply with what the
// table cannot say (a control rate, the estimator's health entries).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "hpa/flight/protocol.h"
#include "message_codecs.h"
#include "message_table.h"
#include "protocol_common.h"

namespace hpa::flight {
namespace {

// Whether `name` is 1 to kMaxNameBytes letters, digits and underscores.
bool IsIdentifier(const std::string& name) {
  if (name.empty() || name.size() > kMaxNameBytes) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
  });
}

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
  ack.uses_pixels = j.value("uses_pixels", true);
  if (ack.detects_at_capture && !ack.uses_pixels) {
    throw ProtocolError(
        "hello_ack's detects_at_capture is true and uses_pixels false: a stack that detects in "
        "each frame at its capture reads its pixels");
  }
  if (ack.batched_ticks && !(ack.control_rate_hz > 0.0 && ack.control_rate_hz <= tick_hz)) {
    throw ProtocolError(
        "hello_ack's batched_ticks needs the control rate its ticks follow: "
        "control_rate_hz is " +
        Shown(j.value("control_rate_hz", nlohmann::json())) + ", expected a rate in (0, " +
        Shown(std::lround(tick_hz)) + "] Hz");
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

}  // namespace hpa::flight
