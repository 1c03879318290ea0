#pragma once
// What the single vehicle's messages and a team's share (private to the flight library, defined
// in protocol.cc): the codecs of the structs both carry, and the reading of a JSON message (its
// object, its protocol_version, its name keys) with the text each refusal shows.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hpa/flight/protocol.h"
#include "message_table.h"

namespace hpa::flight {

/// A body-rate command's codec (tick_reply's and team_tick_reply's command, rate_tick's).
const wire::Codec<BodyRateCommand>& BodyRateCommandCodec();

/// A controller's output's codec (tick_reply's command, team_tick_reply's output).
const wire::Codec<ControlOutput>& ControlOutputCodec();

/// A JSON value as an error message shows it: its text, cut after 60 bytes.
std::string Shown(const nlohmann::json& j);

/// A JSON message of `type` that carries the protocol version (hello_ack, team_hello,
/// team_hello_ack): its object, its protocol_version (the integer kProtocolVersion: 1.9 or
/// 2^32 + 1 are not version 1), then its keys as the message table declares them
/// (CheckJsonMessage); throws ProtocolError naming the message and, for a version, the side
/// reading it (`this_side`: "this simulator").
nlohmann::json ParseVersionedMessage(const std::vector<uint8_t>& body, MessageType type,
                                     const std::string& this_side);

/// An optional string key of a message (absent: `fallback`), at most kMaxNameBytes long; throws
/// ProtocolError naming the message and the key otherwise.
std::string NameField(const nlohmann::json& j, const std::string& what, const char* key,
                      const std::string& fallback);

}  // namespace hpa::flight
