#pragma once
// What the files of the single vehicle's binary messages share (private to the flight library):
// the codecs one message family's file defines and another uses (a tick carries detections and
// frames, a detect_reply a detection; CheckMessageBindings walks them all), a message body
// encoded or decoded by its codec, and a message body read as a JSON object.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "hpa/flight/protocol.h"
#include "message_table.h"

namespace hpa::flight {

/// A payload detection's codec (tick's detections, detect_reply's detection; tick_messages.cc).
const wire::Codec<PayloadDetection>& DetectionCodec();
/// A camera frame's codec (tick's frames, the detect message; tick_messages.cc).
const wire::Codec<CameraFrame>& FrameCodec();
/// The tick's (and the finish's) codec (tick_messages.cc).
const wire::Codec<FlightInputs>& TickCodec();
/// The tick_reply's codec (tick_messages.cc).
const wire::Codec<FlightOutputs>& ReplyCodec();
/// The detect_reply's codec (detect_messages.cc).
const wire::Codec<DetectReply>& DetectReplyCodec();
/// The rate_tick's codec (rate_messages.cc).
const wire::Codec<RateTick>& RateTickCodec();
/// The rate_reply's codec (rate_messages.cc).
const wire::Codec<AutopilotOutput>& RateReplyCodec();

/// A message body encoded by its codec.
template <class T>
std::vector<uint8_t> EncodeBody(const wire::Codec<T>& codec, const T& value) {
  wire::Writer w;
  codec.Encode(value, w);
  return std::move(w.bytes);
}

/// A message body `name` decoded by its codec, every byte of it read.
template <class T>
T DecodeBody(const wire::Codec<T>& codec, const std::vector<uint8_t>& body, const char* name) {
  wire::Reader r(body, name);
  T value;
  codec.Decode(r, value, "");
  r.End();
  return value;
}

/// A message's JSON object; ProtocolError naming the message when it is not one (protocol.cc).
nlohmann::json ParseObject(const std::vector<uint8_t>& body, const std::string& what);

}  // namespace hpa::flight
