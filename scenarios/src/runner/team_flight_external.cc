// The team's separate flight stack(s) over the lockstep protocol (docs/protocol.md, "Teams").

#include "hpa/flight/protocol.h"
#include "scenarios/src/runner/team_flight_link.h"

namespace hpa::runner {

std::unique_ptr<TeamFlightLink> StartExternalTeamFlight(const CooperativeTeam& team,
                                                        const ExternalTeamFlightOptions& options) {
  (void)team;
  throw flight::ProtocolError("flight stack '" + options.command +
                              "': a team's separate flight stacks are not supported yet");
}

}  // namespace hpa::runner
