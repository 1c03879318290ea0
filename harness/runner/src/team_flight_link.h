#pragma once
// How the team runner reaches each vehicle's flight code (private to the runner): in process
// (each vehicle's TeamController called directly) or separate stacks over the lockstep protocol
// (docs/protocol.md, "Teams"). Both see the same views in the same order and answer the same
// replies, so a run's metrics do not depend on where its flight code runs.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hpa/controller/reference_spec.h"
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

/// Settings of a team's separate flight stack(s).
struct ExternalTeamFlightOptions {
  std::string command;           // shell command line that starts a stack
  bool per_vehicle = true;       // one process per vehicle (HPA_VEHICLE set), else one for all
  double step_timeout_s = 10.0;  // longest wait for one reply
  std::string scenario;          // the scenario's name and seed, for the hello
  unsigned long seed = 0;
  std::string controller;   // the scenario's team controller, for the hello
  ReferenceSpec reference;  // the scenario's payload reference, for the hello
};

/// Starts the team's separate stack(s) and completes their hello; throws flight::ProtocolError
/// naming the command for one that does not start, connect or speak the protocol, and
/// flight::WaitInterrupted when a stop (StopRequested) ends a wait. Every reply is checked at this
/// boundary: a stack's bad value ends the run with a run error naming it.
std::unique_ptr<TeamFlightLink> StartExternalTeamFlight(const CooperativeTeam& team,
                                                        const ExternalTeamFlightOptions& options);

/// Every vehicle's controller of `type` in this process (MakeTeamController).
std::unique_ptr<TeamFlightLink> MakeInProcessTeamFlight(
    const std::string& type, const CooperativeTeam& team,
    std::shared_ptr<const Reference> payload_reference);

}  // namespace hpa::runner
