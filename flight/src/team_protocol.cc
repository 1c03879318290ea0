// The team messages of the lockstep protocol (docs/protocol.md, "Teams"): their codecs, bound to
// the message table as the single vehicle's are, and the team_hello / team_hello_ack JSON.

#include "hpa/flight/team_protocol.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "message_table.h"
#include "protocol_common.h"

namespace hpa::flight {
namespace {

using wire::Bind;
using wire::Codec;

// The body of TeamVehicleReply's list, as a C++ struct the codec binds to.
struct TeamTickReply {
  std::vector<TeamVehicleReply> replies;
};

const Codec<TeamView>& TeamViewCodec() {
  static const Codec<TeamView> codec(
      "team_view", {Bind("p_WQ_W", &TeamView::p_WQ_W), Bind("v_WQ_W", &TeamView::v_WQ_W),
                    Bind("q_WB", &TeamView::q_WB), Bind("w_B", &TeamView::w_B),
                    Bind("p_WL_W", &TeamView::p_WL_W), Bind("v_WL_W", &TeamView::v_WL_W),
                    Bind("q_WP", &TeamView::q_WP), Bind("w_P", &TeamView::w_P)});
  return codec;
}

const Codec<TeamVehicleView>& TeamVehicleViewCodec() {
  static const Codec<TeamVehicleView> codec(
      "team_vehicle_view", {Bind("vehicle", &TeamVehicleView::vehicle),
                            Bind("view", &TeamVehicleView::view, TeamViewCodec())});
  return codec;
}

const Codec<TeamTick>& TeamTickCodec() {
  static const Codec<TeamTick> codec(
      "team_tick",
      {Bind("time_s", &TeamTick::time_s), Bind("views", &TeamTick::views, TeamVehicleViewCodec())});
  return codec;
}

const Codec<TeamVehicleReply>& TeamVehicleReplyCodec() {
  static const Codec<TeamVehicleReply> codec(
      "team_vehicle_reply", {Bind("vehicle", &TeamVehicleReply::vehicle),
                             Bind("output", &TeamVehicleReply::output, ControlOutputCodec()),
                             Bind("cable_taut", &TeamVehicleReply::cable_taut)});
  return codec;
}

const Codec<TeamTickReply>& TeamTickReplyCodec() {
  static const Codec<TeamTickReply> codec(
      "team_tick_reply", {Bind("replies", &TeamTickReply::replies, TeamVehicleReplyCodec())});
  return codec;
}

// A finite number at `key` of j (`what` names j), > 0 when `positive`.
double FiniteNumber(const nlohmann::json& j, const char* key, const std::string& what,
                    bool positive) {
  const nlohmann::json& v = j.at(key);
  if (!v.is_number() || !std::isfinite(v.get<double>()) || (positive && !(v.get<double>() > 0))) {
    throw ProtocolError(what + "'s " + key + " is " + Shown(v) + ", expected a finite number" +
                        (positive ? " > 0" : ""));
  }
  return v.get<double>();
}

// Three finite numbers at `key` of j (`what` names j).
Eigen::Vector3d FiniteVec3(const nlohmann::json& j, const char* key, const std::string& what) {
  const nlohmann::json& v = j.at(key);
  const bool ok =
      v.is_array() && v.size() == 3 && std::all_of(v.begin(), v.end(), [](const nlohmann::json& x) {
        return x.is_number() && std::isfinite(x.get<double>());
      });
  if (!ok) throw ProtocolError(what + "'s " + key + " is " + Shown(v) + ", expected 3 numbers");
  return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
}

nlohmann::json Vec3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

// A list of vehicle indices: distinct integers in [0, n), ascending.
std::vector<int> VehicleList(const nlohmann::json& v, size_t n, const std::string& what) {
  std::vector<int> out;
  bool ok = v.is_array() && !v.empty();
  for (size_t i = 0; ok && i < v.size(); ++i) {
    ok = v[i].is_number_integer() && v[i].get<int64_t>() >= 0 && v[i].get<uint64_t>() < n &&
         (out.empty() || v[i].get<int>() > out.back());
    if (ok) out.push_back(v[i].get<int>());
  }
  if (!ok) {
    throw ProtocolError(what + " is " + Shown(v) + ", expected ascending vehicle indices in [0, " +
                        std::to_string(n) + ")");
  }
  return out;
}

// A list of vehicles as an error message names it ("vehicle 1", "vehicles 0, 1, 2").
std::string VehiclesShown(const std::vector<int>& vehicles) {
  std::string out = vehicles.size() == 1 ? "vehicle " : "vehicles ";
  for (size_t i = 0; i < vehicles.size(); ++i) {
    out += (i == 0 ? "" : ", ") + std::to_string(vehicles[i]);
  }
  return out;
}

}  // namespace

std::vector<uint8_t> EncodeTeamTick(const TeamTick& tick) {
  wire::Writer w;
  TeamTickCodec().Encode(tick, w);
  return std::move(w.bytes);
}

TeamTick DecodeTeamTick(const std::vector<uint8_t>& body) {
  wire::Reader r(body, "team_tick");
  TeamTick tick;
  TeamTickCodec().Decode(r, tick, "");
  r.End();
  for (TeamVehicleView& v : tick.views) v.view.time_s = tick.time_s;
  return tick;
}

std::vector<uint8_t> EncodeTeamTickReply(const std::vector<TeamVehicleReply>& replies) {
  wire::Writer w;
  TeamTickReplyCodec().Encode(TeamTickReply{replies}, w);
  return std::move(w.bytes);
}

std::vector<TeamVehicleReply> DecodeTeamTickReply(const std::vector<uint8_t>& body) {
  // reply by reply, so a refusal names the vehicle whose reply it is (its index comes first)
  wire::Reader r(body, "team_tick_reply");
  const wire::Field& list = TeamTickReplyCodec().spec().fields.front();
  std::vector<TeamVehicleReply> replies(r.Count(list));
  for (size_t i = 0; i < replies.size(); ++i) {
    try {
      TeamVehicleReplyCodec().Decode(r, replies[i], list.item + " " + std::to_string(i));
    } catch (const WaitInterrupted&) {
      throw;
    } catch (const ProtocolError& e) {
      throw ProtocolError(std::string(e.what()) + " (reply " + std::to_string(i) + ", vehicle " +
                          std::to_string(replies[i].vehicle) + ")");
    }
  }
  r.End();
  return replies;
}

void CheckTeamTickReply(const std::vector<TeamVehicleReply>& replies, const TeamTick& tick) {
  if (replies.size() != tick.views.size()) {
    throw ProtocolError("team_tick_reply refused: " + std::to_string(replies.size()) +
                        " replies to a team_tick of " + std::to_string(tick.views.size()) +
                        " view(s)");
  }
  for (size_t i = 0; i < replies.size(); ++i) {
    if (replies[i].vehicle != tick.views[i].vehicle) {
      throw ProtocolError("team_tick_reply refused: reply " + std::to_string(i) +
                          " is for vehicle " + std::to_string(replies[i].vehicle) +
                          ", expected vehicle " + std::to_string(tick.views[i].vehicle) +
                          " (the team_tick's view " + std::to_string(i) + ")");
    }
  }
}

void CheckTeamMessageBindings() {
  TeamTickCodec();
  TeamTickReplyCodec();
}

nlohmann::json TeamHelloToJson(const TeamHello& hello) {
  nlohmann::json vehicles = nlohmann::json::array();
  for (const CooperativeVehicle& v : hello.team.vehicles) {
    vehicles.push_back({{"params", ParamsToJson(v.params)},
                        {"cable_length_m", v.cable_length_m},
                        {"p_PA_P_m", Vec3(v.p_PA_P_m)}});
  }
  return {{"protocol_version", kProtocolVersion},
          {"scenario", hello.scenario},
          {"seed", hello.seed},
          {"vehicles", hello.vehicles},
          {"controller", hello.controller},
          {"team",
           {{"payload_mass_kg", hello.team.payload_mass_kg},
            {"payload_inertia_P_kgm2", Vec3(hello.team.payload_inertia_P_kgm2)},
            {"gravity_mps2", hello.team.gravity_mps2},
            {"vehicles", vehicles}}},
          {"reference", ReferenceToJson(hello.reference)}};
}

TeamHello ParseTeamHello(const std::vector<uint8_t>& body) {
  const std::string what = "team_hello";
  const nlohmann::json j = ParseVersionedMessage(body, MessageType::kTeamHello, "this side");
  TeamHello hello;
  hello.scenario = j.at("scenario").get<std::string>();
  hello.seed = j.at("seed").get<uint64_t>();
  hello.controller = j.at("controller").get<std::string>();
  const std::vector<std::string>& names = TeamControllerNames();
  if (std::find(names.begin(), names.end(), hello.controller) == names.end()) {
    throw ProtocolError(what + "'s controller is " + Shown(j.at("controller")) +
                        ", a team controller this stack does not have");
  }
  // the team: the payload, then each vehicle's params, cable and attachment point
  const nlohmann::json& tj = j.at("team");
  const std::string team = what + "'s team";
  CooperativeTeam& t = hello.team;
  t.payload_mass_kg = FiniteNumber(tj, "payload_mass_kg", team, true);
  t.payload_inertia_P_kgm2 = FiniteVec3(tj, "payload_inertia_P_kgm2", team);
  t.gravity_mps2 = FiniteNumber(tj, "gravity_mps2", team, false);
  const nlohmann::json& vj = tj.at("vehicles");
  if (vj.empty()) throw ProtocolError(team + " has no vehicles");
  for (size_t i = 0; i < vj.size(); ++i) {
    const std::string where = team + "'s vehicle " + std::to_string(i);
    if (!vj[i].is_object() || !vj[i].contains("params")) {
      throw ProtocolError(where + " is " + Shown(vj[i]) +
                          ", expected {params, cable_length_m, p_PA_P_m}");
    }
    CooperativeVehicle v;
    v.params =
        ParamsFromJson(vj[i].at("params"), "team.vehicles[" + std::to_string(i) + "].params");
    v.cable_length_m = FiniteNumber(vj[i], "cable_length_m", where, true);
    v.p_PA_P_m = FiniteVec3(vj[i], "p_PA_P_m", where);
    t.vehicles.push_back(v);
  }
  hello.vehicles = VehicleList(j.at("vehicles"), t.vehicles.size(), what + "'s vehicles");
  hello.reference = ReferenceFromJson(j.at("reference"));
  return hello;
}

TeamHelloAck ParseTeamHelloAck(const std::vector<uint8_t>& body, const std::vector<int>& vehicles,
                               double tick_hz) {
  const std::string what = "team_hello_ack";
  const nlohmann::json j = ParseVersionedMessage(body, MessageType::kTeamHelloAck, "this side");
  TeamHelloAck ack;
  ack.name = NameField(j, what, "name", "external");
  ack.controller = NameField(j, what, "controller", "");
  const double rate_hz = j.at("control_rate_hz").get<double>();
  if (!(std::isfinite(rate_hz) && rate_hz > 0.0 && rate_hz <= tick_hz)) {
    throw ProtocolError(what + "'s control_rate_hz is " + Shown(j.at("control_rate_hz")) +
                        ", expected a rate in (0, " + Shown(std::lround(tick_hz)) + "] Hz");
  }
  ack.control_rate_hz = rate_hz;
  const nlohmann::json& v = j.at("vehicles");
  const bool same =
      v.is_array() && v.size() == vehicles.size() &&
      std::equal(vehicles.begin(), vehicles.end(), v.begin(), [](int a, const nlohmann::json& b) {
        return b.is_number_integer() && b.get<int64_t>() == a;
      });
  if (!same) {
    throw ProtocolError(what + "'s vehicles are " + Shown(v) + ", expected the team_hello's (" +
                        VehiclesShown(vehicles) + ")");
  }
  ack.vehicles = vehicles;
  return ack;
}

}  // namespace hpa::flight
