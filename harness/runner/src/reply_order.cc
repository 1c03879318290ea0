// The order of a separate flight stack's replies (reply_order.h).
#include "harness/runner/src/reply_order.h"

#include <vector>

namespace hpa::runner {

using flight::ProtocolError;

void ReplyOrder::TickAnswered(const flight::FlightOutputs& reply, double tick_s) {
  if (reply.has_estimate && reply.estimate.time_s != tick_s) {
    if (stamps_ticks_ && last_tick_answered_s_ &&
        reply.estimate.time_s == *last_tick_answered_s_) {
      throw ProtocolError("a second reply to the " + last_answered_ +
                          ": the reply read for the tick at t = " + std::to_string(tick_s) +
                          " s carries that tick's time (its estimate's time_s), where every "
                          "reply before it carried its own tick's (a stack answers each message "
                          "once)");
    }
    stamps_ticks_ = false;
  }
  last_tick_answered_s_ = tick_s;
  last_answered_ = "tick at t = " + std::to_string(tick_s) + " s";
}

void ReplyOrder::CheckNothingUnasked(flight::Channel& channel,
                                     const flight::WaitLimit& limit) const {
  if (!channel.HasUnread()) return;
  std::vector<uint8_t> body;
  const flight::MessageType type = channel.Receive(&body, limit);
  throw ProtocolError("a second reply to the " + last_answered_ + ": a " +
                      flight::MessageTypeName(type) +
                      " message arrived before the next message was sent (a stack answers each "
                      "message once)");
}

}  // namespace hpa::runner
