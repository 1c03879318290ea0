#pragma once
// How the team runner reaches each vehicle's flight code (private to the runner): in process
// (each vehicle's TeamController called directly) or separate stacks over the lockstep protocol
// (docs/protocol.md, "Teams"). Both see the same views in the same order and answer the same
// replies, so a run's metrics do not depend on where its flight code runs.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hpa/controller/team_controller.h"
#include "hpa/models/cooperative_model.h"

namespace hpa::runner {

/// What one vehicle's flight code answered at a control step.
struct TeamReply {
  ControlOutput output;    // its command and status (solve_time_ms: the update's wall time)
  bool cable_taut = true;  // its reading of its own cable
};

/// One team run's connection to its vehicles' flight code.
class TeamFlightLink {
 public:
  virtual ~TeamFlightLink() = default;
  /// Each vehicle's reply to its view at this control step: views[i] is vehicle i's; a vehicle
  /// without a view yet (its first readings still in flight) is not asked and its reply is empty.
  virtual std::vector<std::optional<TeamReply>> Step(
      const std::vector<std::optional<TeamView>>& views) = 0;
  /// The rate (Hz) the team's controllers run at, the same for every vehicle.
  virtual double RateHz() const = 0;
  /// What flies: "in_process", or the name the separate stack(s) gave in their hello.
  virtual std::string name() const = 0;
  /// The controller that flies, for metrics.json: the scenario's in process, a separate stack's
  /// own name for its controller.
  virtual std::string controller() const = 0;
  /// Ends the run: a separate stack is told and waited for.
  virtual void Finish() {}
};

/// Every vehicle's controller of `type` in this process (MakeTeamController).
std::unique_ptr<TeamFlightLink> MakeInProcessTeamFlight(
    const std::string& type, const CooperativeTeam& team,
    std::shared_ptr<const Reference> payload_reference);

}  // namespace hpa::runner
