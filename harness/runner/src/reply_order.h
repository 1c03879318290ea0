#pragma once
// The order of a separate flight stack's replies (private to the runner): in lockstep a stack
// answers each message once, so a second reply to one message is refused where it shows, naming
// the message it answered twice, instead of being read as the next message's reply.

#include <optional>
#include <string>

#include "hpa/flight/protocol.h"

namespace hpa::runner {

/// What a separate stack has answered so far, and the checks that find a second reply.
class ReplyOrder {
 public:
  /// Notes the reply read as the one to the tick at `tick_s`. Throws flight::ProtocolError when
  /// it is the tick before's second reply, which the read order alone cannot tell (the stack's
  /// next reply is still on its way when the next tick is sent): its estimate carries the time of
  /// the tick answered before (time_s), from a stack whose every reply so far carried its own
  /// tick's time (as hpa-flight's and the Python client's do; a stack that stamps otherwise is not
  /// judged by it).
  void TickAnswered(const flight::FlightOutputs& reply, double tick_s);

  /// Notes the reply to another message (`what`: "detect at t = 0.100000 s").
  void Answered(std::string what) { last_answered_ = std::move(what); }

  /// Throws flight::ProtocolError naming the message last answered when bytes from the stack wait
  /// unread on `channel` while no reply is awaited (a stack's error message among them is
  /// reported as its own words; the message is read within `limit`).
  void CheckNothingUnasked(flight::Channel& channel, const flight::WaitLimit& limit) const;

 private:
  std::string last_answered_ = "hello";         // the last message whose reply was read
  std::optional<double> last_tick_answered_s_;  // the time of the last tick whose reply was read
  bool stamps_ticks_ = true;  // every reply's estimate so far carried its own tick's time
};

}  // namespace hpa::runner
