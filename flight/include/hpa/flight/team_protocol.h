#pragma once
// The lockstep protocol's team messages (docs/protocol.md, "Teams"): a stack that flies vehicles
// of a team carrying one payload (one stack per vehicle, or one for the whole team) is greeted
// with team_hello (the team, its controller, the payload reference, the vehicles it flies) and
// answers team_hello_ack; at each of the team's control steps it gets team_tick (each of its
// vehicles' TeamView) and answers team_tick_reply (each one's ControlOutput and cable reading).
// The binary layouts are declared in the message table (python/hpa_sim/messages.json) beside
// the single vehicle's, which they leave unchanged.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hpa/controller/controller.h"
#include "hpa/controller/reference_spec.h"
#include "hpa/controller/team_controller.h"
#include "hpa/flight/protocol.h"
#include "hpa/models/cooperative_model.h"

namespace hpa::flight {

/// One vehicle's view in a team_tick.
struct TeamVehicleView {
  int vehicle = 0;  // its index in the team
  TeamView view;    // what its flight code knows now (view.time_s: the tick's time)
};

/// One control step of a team, for the vehicles a stack flies (those with a view).
struct TeamTick {
  double time_s = 0.0;                 // simulated time of the control step
  std::vector<TeamVehicleView> views;  // by vehicle index
};

/// One vehicle's answer in a team_tick_reply.
struct TeamVehicleReply {
  int vehicle = 0;         // its index in the team (the view's it answers)
  ControlOutput output;    // its command, status, solve time (ms) and cost
  bool cable_taut = true;  // whether its controller sees its cable taut now
};

/// Encodes a team_tick.
std::vector<uint8_t> EncodeTeamTick(const TeamTick& tick);
/// Decodes a team_tick (each view's time_s set to the tick's); throws ProtocolError as
/// DecodeTick does.
TeamTick DecodeTeamTick(const std::vector<uint8_t>& body);
/// Encodes a team_tick_reply.
std::vector<uint8_t> EncodeTeamTickReply(const std::vector<TeamVehicleReply>& replies);
/// Decodes a team_tick_reply; throws ProtocolError naming the vehicle, the field and the value
/// for a value the message table refuses (a non-finite command, an unknown status, a solve time
/// outside [0, an hour], a negative or non-finite cost, a cable_taut other than 0 or 1).
std::vector<TeamVehicleReply> DecodeTeamTickReply(const std::vector<uint8_t>& body);
/// Checks a decoded team_tick_reply against the team_tick it answers: throws ProtocolError
/// naming the reply and the vehicle for a reply count other than the views', or a reply whose
/// vehicle is not its view's.
void CheckTeamTickReply(const std::vector<TeamVehicleReply>& replies, const TeamTick& tick);
/// Binds the team messages' C++ structs to the message table (CheckMessageBindings' part for
/// them); throws std::logic_error as it does.
void CheckTeamMessageBindings();

/// What a team's stack is told in its team_hello.
struct TeamHello {
  std::string scenario;       // the scenario's name
  uint64_t seed = 0;          // and its seed
  std::vector<int> vehicles;  // the vehicles the stack flies, ascending
  std::string controller;     // the team controller every vehicle flies (TeamControllerNames)
  CooperativeTeam team;       // the team as the simulator flies it
  ReferenceSpec reference;    // the payload reference (the stack builds the same Reference)
};

/// The team_hello's JSON (protocol_version kProtocolVersion); doubles keep every bit.
nlohmann::json TeamHelloToJson(const TeamHello& hello);
/// Parses a team_hello; throws ProtocolError naming the key for a protocol version other than
/// kProtocolVersion, a key the table does not declare or lacks, a team that is not 1 or more
/// vehicles with finite positive masses, cable lengths and finite attachment points, params
/// outside their declared ranges, vehicles that are not distinct indices into the team, a
/// controller this side does not have, or a reference it cannot build.
TeamHello ParseTeamHello(const std::vector<uint8_t>& body);

/// A team's stack's team_hello_ack.
struct TeamHelloAck {
  std::string name = "external";  // the stack's name (metrics.json's flight_stack)
  std::string controller;         // what flies, metrics.json's controller ("": its name)
  double control_rate_hz = 0.0;   // the rate its controllers run at
  std::vector<int> vehicles;      // the vehicles it flies
};

/// Parses a team_hello_ack answering a team_hello for `vehicles`; throws ProtocolError naming
/// the key and value for a protocol_version that is not the integer kProtocolVersion, a key the
/// table does not declare or lacks, a name or controller that is not a string of at most
/// kMaxNameBytes, a control rate that is not in (0, tick_hz], or vehicles other than `vehicles`.
TeamHelloAck ParseTeamHelloAck(const std::vector<uint8_t>& body, const std::vector<int>& vehicles,
                               double tick_hz = 1000.0);

}  // namespace hpa::flight
