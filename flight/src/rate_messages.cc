// The rate_tick and its rate_reply (docs/protocol.md): one step of the vehicle's rate loop sent to
// a stack that owns the loop, and that step's rotor speed commands, with their codecs and the
// check of a reply's commands against the motors' range.

#include <cstdint>
#include <string>
#include <vector>

#include "hpa/flight/protocol.h"
#include "message_codecs.h"
#include "message_table.h"
#include "protocol_common.h"

namespace hpa::flight {

using wire::Bind;
using wire::Codec;

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

}  // namespace hpa::flight
