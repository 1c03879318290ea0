// The check that every binary message's C++ structs are bound to the message table, and every
// struct of the table to a message (CheckMessageBindings).

#include <set>
#include <stdexcept>
#include <string>

#include "hpa/flight/protocol.h"
#include "hpa/flight/team_protocol.h"
#include "message_codecs.h"
#include "message_table.h"

namespace hpa::flight {

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

}  // namespace hpa::flight
