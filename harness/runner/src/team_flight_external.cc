// The team's separate flight stack(s) over the lockstep protocol (docs/protocol.md, "Teams"):
// one process per vehicle (each started with HPA_VEHICLE set to its index) or one for the whole
// team, each serving its own socket as a single vehicle's stack does (stack_process.h: the
// process group, HPA_FLIGHT_SOCKET, the cleanup). At each control step every stack with views
// gets its team_tick before any reply is read, so per-vehicle stacks compute side by side; the
// replies are read in vehicle order and checked where they arrive.

#include <algorithm>
#include <optional>
#include <utility>

#include "hpa/flight/protocol.h"
#include "hpa/flight/team_protocol.h"
#include "hpa/sim/world.h"
#include "harness/runner/src/flight_process.h"
#include "harness/runner/src/reply_order.h"
#include "harness/runner/src/stack_process.h"
#include "harness/runner/src/team_flight_link.h"

namespace hpa::runner {
namespace {

using flight::Channel;
using flight::MessageType;
using flight::ProtocolError;
using Clock = StackProcess::Clock;

// One stack process of the team: its socket, its process and the vehicles it flies.
class TeamStack {
 public:
  // `vehicle_env`: the HPA_VEHICLE it is started with (-1: none, it flies the whole team).
  TeamStack(const ExternalTeamFlightOptions& options, std::vector<int> vehicles, int vehicle_env)
      : options_(options),
        vehicles_(std::move(vehicles)),
        vehicle_env_(vehicle_env),
        process_(Who(), options.step_timeout_s) {}

  // Serves its socket and starts its process, with the vehicle it flies in its environment
  // beside HPA_FLIGHT_SOCKET.
  void Start() {
    if (vehicle_env_ < 0) {
      process_.Start(options_.command);
    } else {
      process_.Start(options_.command, {{"HPA_VEHICLE", std::to_string(vehicle_env_)}});
    }
  }

  // Waits for it to connect until `deadline`, polling for its end and for a stop signal.
  void Accept(Clock::time_point deadline) { process_.Accept(deadline, kConnectTimeoutS); }

  // Sends its team_hello.
  void SendHello(const flight::TeamHello& hello) {
    process_.Guard(
        [&] {
          channel().SendJson(MessageType::kTeamHello, flight::TeamHelloToJson(hello), Limit());
        },
        "team_hello");
  }

  // Reads and checks its team_hello_ack.
  flight::TeamHelloAck ReadHelloAck() {
    flight::TeamHelloAck ack;
    process_.Guard(
        [&] {
          ack = flight::ParseTeamHelloAck(channel().Expect(MessageType::kTeamHelloAck, Limit()),
                                          vehicles_, 1.0 / sim::World::kPhysicsDt_s);
        },
        "team_hello");
    replies_.Answered("team_hello");
    return ack;
  }

  // Sends a team_tick (its reply is read by ReadReply).
  void SendTick(const flight::TeamTick& tick) {
    process_.Guard(
        [&] {
          replies_.CheckNothingUnasked(channel(), Limit());
          channel().Send(MessageType::kTeamTick, flight::EncodeTeamTick(tick), Limit());
        },
        Step(tick.time_s));
  }

  // Reads the reply to `tick` and checks it against it.
  std::vector<flight::TeamVehicleReply> ReadReply(const flight::TeamTick& tick) {
    std::vector<flight::TeamVehicleReply> replies;
    process_.Guard(
        [&] {
          replies =
              flight::DecodeTeamTickReply(channel().Expect(MessageType::kTeamTickReply, Limit()));
          flight::CheckTeamTickReply(replies, tick);
        },
        Step(tick.time_s));
    replies_.Answered(Step(tick.time_s));
    return replies;
  }

  // Whether it may be asked for its finish (not failed, not past a stop's grace).
  bool Finishable() { return process_.Finishable(); }

  // Sends the finish (an empty tick at time_s).
  void SendFinish(double time_s) {
    flight::FlightInputs in;
    in.time_s = time_s;
    process_.Guard(
        [&] {
          replies_.CheckNothingUnasked(channel(), Limit());
          channel().Send(MessageType::kFinish, flight::EncodeTick(in), Limit());
        },
        "finish");
  }

  // Reads and checks its finish_reply.
  void ReadFinish() {
    process_.Guard(
        [&] { flight::ParseFinishReply(channel().Expect(MessageType::kFinishReply, Limit()), 0); },
        "finish");
  }

  const std::vector<int>& vehicles() const { return vehicles_; }

 private:
  // The connection to the stack, and one message's wait on it.
  Channel& channel() { return process_.channel(); }
  flight::WaitLimit Limit() { return process_.Limit(); }

  // A control step as error messages name it.
  static std::string Step(double time_s) {
    return "team_tick at t = " + std::to_string(time_s) + " s";
  }

  // The stack as error messages name it: its command, and its vehicle when it flies one.
  std::string Who() const {
    return "flight stack '" + options_.command + "'" +
           (vehicle_env_ >= 0 ? " (vehicle " + std::to_string(vehicle_env_) + ")" : "");
  }

  const ExternalTeamFlightOptions& options_;
  std::vector<int> vehicles_;  // the vehicles it flies, ascending
  int vehicle_env_;            // its HPA_VEHICLE (-1: none)
  StackProcess process_;       // its process and socket
  ReplyOrder replies_;  // what it answered so far: a second reply is refused before the next send
};

// The team's separate stacks: one per vehicle, or one for all.
class ExternalTeamFlight final : public TeamFlightLink {
 public:
  ExternalTeamFlight(const CooperativeTeam& team, const ExternalTeamFlightOptions& options)
      : options_(options) {
    const int n = static_cast<int>(team.vehicles.size());
    if (options_.per_vehicle) {
      for (int i = 0; i < n; ++i)
        stacks_.push_back(std::make_unique<TeamStack>(options_, std::vector<int>{i}, i));
    } else {
      std::vector<int> all;
      for (int i = 0; i < n; ++i) all.push_back(i);
      stacks_.push_back(std::make_unique<TeamStack>(options_, all, -1));
    }
    // what earlier runs of killed hpa processes left behind, before this run adds its own
    RemoveStaleFlightRuns();
    // every process started first, so they start up side by side
    for (const auto& s : stacks_) s->Start();
    const auto deadline = StackProcess::After(kConnectTimeoutS);
    for (const auto& s : stacks_) s->Accept(deadline);
    flight::TeamHello hello;
    hello.scenario = options_.scenario;
    hello.seed = options_.seed;
    hello.controller = options_.controller;
    hello.team = team;
    hello.reference = options_.reference;
    for (const auto& s : stacks_) {
      hello.vehicles = s->vehicles();
      s->SendHello(hello);
    }
    for (size_t k = 0; k < stacks_.size(); ++k) {
      const flight::TeamHelloAck ack = stacks_[k]->ReadHelloAck();
      if (k == 0) {
        name_ = ack.name;
        // a stack that names no controller flies its own: its name labels the run
        controller_ = !ack.controller.empty() ? ack.controller : ack.name;
        rate_hz_ = ack.control_rate_hz;
      } else if (ack.control_rate_hz != rate_hz_) {
        throw ProtocolError("flight stack '" + options_.command + "': vehicle " +
                            std::to_string(k) + "'s stack runs its controller at " +
                            std::to_string(ack.control_rate_hz) + " Hz, vehicle 0's at " +
                            std::to_string(rate_hz_) + " Hz (a team shares one control rate)");
      }
    }
  }

  std::vector<std::optional<TeamReply>> Step(
      const std::vector<std::optional<TeamView>>& views) override {
    std::vector<std::optional<TeamReply>> replies(views.size());
    // every stack's tick goes out before any reply is read
    std::vector<flight::TeamTick> ticks(stacks_.size());
    for (size_t k = 0; k < stacks_.size(); ++k) {
      flight::TeamTick& tick = ticks[k];
      for (const int i : stacks_[k]->vehicles()) {
        const std::optional<TeamView>& view = views[static_cast<size_t>(i)];
        if (!view) continue;
        tick.time_s = view->time_s;
        tick.views.push_back({i, *view});
      }
      if (!tick.views.empty()) stacks_[k]->SendTick(tick);
      last_time_s_ = std::max(last_time_s_, tick.time_s);
    }
    for (size_t k = 0; k < stacks_.size(); ++k) {
      if (ticks[k].views.empty()) continue;
      for (const flight::TeamVehicleReply& r : stacks_[k]->ReadReply(ticks[k])) {
        TeamReply& reply = replies[static_cast<size_t>(r.vehicle)].emplace();
        reply.output = r.output;
        reply.cable_taut = r.cable_taut;
      }
    }
    return replies;
  }

  double RateHz() const override { return rate_hz_; }
  std::string name() const override { return name_; }
  std::string controller() const override { return controller_; }

  void Finish() override {
    std::vector<TeamStack*> asked;
    for (const auto& s : stacks_) {
      if (!s->Finishable()) continue;
      s->SendFinish(last_time_s_);
      asked.push_back(s.get());
    }
    for (TeamStack* s : asked) s->ReadFinish();
  }

 private:
  ExternalTeamFlightOptions options_;
  std::vector<std::unique_ptr<TeamStack>> stacks_;  // in vehicle order
  std::string name_ = "external", controller_ = "external";
  double rate_hz_ = 0.0;      // the stacks' control rate (Hz)
  double last_time_s_ = 0.0;  // the last control step's time
};

}  // namespace

std::unique_ptr<TeamFlightLink> StartExternalTeamFlight(const CooperativeTeam& team,
                                                        const ExternalTeamFlightOptions& options) {
  return std::make_unique<ExternalTeamFlight>(team, options);
}

}  // namespace hpa::runner
