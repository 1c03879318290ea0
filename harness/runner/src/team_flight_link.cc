#include "harness/runner/src/team_flight_link.h"

#include <chrono>

namespace hpa::runner {
namespace {

// The team's controllers in this process, one per vehicle.
class InProcessTeamFlight final : public TeamFlightLink {
 public:
  InProcessTeamFlight(const std::string& type, const CooperativeTeam& team,
                      const std::shared_ptr<const Reference>& payload_reference)
      : type_(type) {
    for (int i = 0; i < static_cast<int>(team.vehicles.size()); ++i) {
      controllers_.push_back(MakeTeamController(type, team, i, payload_reference));
    }
  }

  std::vector<std::optional<TeamReply>> Step(
      const std::vector<std::optional<TeamView>>& views) override {
    using Clock = std::chrono::steady_clock;
    std::vector<std::optional<TeamReply>> replies(views.size());
    for (size_t i = 0; i < views.size() && i < controllers_.size(); ++i) {
      if (!views[i]) continue;
      // the update's wall time measured here, the same way for every team controller (one that
      // does not time itself would otherwise report zero)
      const Clock::time_point start = Clock::now();
      TeamReply reply;
      reply.output = controllers_[i]->Update(*views[i]);
      reply.output.solve_time_ms =
          std::chrono::duration<double, std::milli>(Clock::now() - start).count();
      reply.cable_taut = controllers_[i]->CableTaut();
      replies[i] = reply;
    }
    return replies;
  }

  double RateHz() const override { return controllers_.front()->RateHz(); }
  std::string name() const override { return "in_process"; }
  std::string controller() const override { return type_; }

 private:
  std::string type_;
  std::vector<std::unique_ptr<TeamController>> controllers_;
};

}  // namespace

std::unique_ptr<TeamFlightLink> MakeInProcessTeamFlight(
    const std::string& type, const CooperativeTeam& team,
    std::shared_ptr<const Reference> payload_reference) {
  return std::make_unique<InProcessTeamFlight>(type, team, payload_reference);
}

}  // namespace hpa::runner
