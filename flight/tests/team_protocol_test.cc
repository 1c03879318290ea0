// The team messages of the lockstep protocol (team_protocol.h): team_tick and team_tick_reply
// cross with every bit, a reply the message table or its team_tick refuses is refused naming
// the vehicle and the value, and team_hello / team_hello_ack carry the team, its reference and
// the vehicles a stack flies, refusing what does not fit.

#include "hpa/flight/team_protocol.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "flight/tests/protocol_samples.h"

namespace hpa::flight {
namespace {

// The message ProtocolError `f` throws ("(accepted)" when it throws none).
template <class F>
std::string Refusal(F&& f) {
  try {
    f();
  } catch (const ProtocolError& e) {
    return e.what();
  }
  return "(accepted)";
}

std::vector<uint8_t> Bytes(const nlohmann::json& j) {
  const std::string text = j.dump();
  return {text.begin(), text.end()};
}

// A two-vehicle team on a line reference, as a team_hello for vehicle 1.
TeamHello SampleHello() {
  TeamHello hello;
  hello.scenario = "team2_line";
  hello.seed = 7;
  hello.vehicles = {1};
  hello.controller = "cooperative";
  hello.team.payload_mass_kg = 0.2;
  hello.team.payload_inertia_P_kgm2 = {1.3e-4, 8.2e-3, 8.2e-3};
  for (const double x_m : {0.35, -0.35}) {
    CooperativeVehicle v;
    v.cable_length_m = 0.5 + 1.0 / 3.0;
    v.p_PA_P_m = {x_m, 0.0, -0.0};
    hello.team.vehicles.push_back(v);
  }
  hello.reference.type = "line";
  hello.reference.line_start_W_m = {-1.5, 0.0, 0.8};
  hello.reference.line_end_W_m = {1.5, 0.1, 0.8};
  hello.reference.line_duration_s = 6.0;
  hello.reference.line_start_time_s = 1.0 / 3.0;
  return hello;
}

TEST(TeamProtocolTest, TicksAndRepliesCrossWithEveryBit) {
  const TeamTick tick = SampleTeamTick();
  const TeamTick back = DecodeTeamTick(EncodeTeamTick(tick));
  EXPECT_EQ(back.time_s, tick.time_s);
  ASSERT_EQ(back.views.size(), tick.views.size());
  for (size_t i = 0; i < tick.views.size(); ++i) {
    const TeamView& a = tick.views[i].view;
    const TeamView& b = back.views[i].view;
    EXPECT_EQ(back.views[i].vehicle, tick.views[i].vehicle);
    EXPECT_EQ(b.time_s, tick.time_s);
    EXPECT_EQ(b.p_WQ_W, a.p_WQ_W);
    EXPECT_EQ(b.v_WQ_W, a.v_WQ_W);
    EXPECT_TRUE(std::signbit(b.v_WQ_W.y()));
    EXPECT_EQ(b.q_WB.coeffs(), a.q_WB.coeffs());
    EXPECT_EQ(b.w_B, a.w_B);
    EXPECT_EQ(b.p_WL_W, a.p_WL_W);
    EXPECT_EQ(b.v_WL_W, a.v_WL_W);
    EXPECT_EQ(b.q_WP.coeffs(), a.q_WP.coeffs());
    EXPECT_EQ(b.w_P, a.w_P);
  }
  // a view crosses as measured: a non-finite reading reaches the controller, which levels out
  TeamTick bad = tick;
  bad.views[0].view.p_WL_W.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(std::isnan(DecodeTeamTick(EncodeTeamTick(bad)).views[0].view.p_WL_W.x()));

  const std::vector<TeamVehicleReply> replies = SampleTeamTickReply();
  const std::vector<TeamVehicleReply> got = DecodeTeamTickReply(EncodeTeamTickReply(replies));
  ASSERT_EQ(got.size(), replies.size());
  for (size_t i = 0; i < replies.size(); ++i) {
    EXPECT_EQ(got[i].vehicle, replies[i].vehicle);
    EXPECT_EQ(got[i].output.command.w_B_radps, replies[i].output.command.w_B_radps);
    EXPECT_EQ(got[i].output.command.thrust_N, replies[i].output.command.thrust_N);
    EXPECT_EQ(got[i].output.status, replies[i].output.status);
    EXPECT_EQ(got[i].output.solve_time_ms, replies[i].output.solve_time_ms);
    EXPECT_EQ(got[i].output.cost, replies[i].output.cost);
    EXPECT_EQ(got[i].cable_taut, replies[i].cable_taut);
  }
  EXPECT_NO_THROW(CheckTeamTickReply(got, tick));
}

TEST(TeamProtocolTest, BadRepliesAreRefusedNamingTheVehicleAndTheValue) {
  const TeamTick tick = SampleTeamTick();  // views of vehicles 0 and 2
  std::vector<TeamVehicleReply> replies = SampleTeamTickReply();
  replies[1].output.command.thrust_N = std::numeric_limits<double>::infinity();
  EXPECT_EQ(Refusal([&] { DecodeTeamTickReply(EncodeTeamTickReply(replies)); }),
            "malformed team_tick_reply message: a non-finite command (body rate or thrust) "
            "(reply 1, vehicle 2)");
  replies = SampleTeamTickReply();
  replies[0].output.solve_time_ms = -1.0;
  EXPECT_EQ(Refusal([&] { DecodeTeamTickReply(EncodeTeamTickReply(replies)); }),
            "malformed team_tick_reply message: solve time -1 ms, expected a time in [0, 3600000] "
            "ms (reply 0, vehicle 0)");
  // a status outside 0..5, a cable_taut other than 0 or 1: bytes the encoder cannot write
  std::vector<uint8_t> bytes = EncodeTeamTickReply(SampleTeamTickReply());
  const size_t status_at = 4 + 4 + 4 * 8;  // count, vehicle, command
  bytes[status_at] = 9;
  EXPECT_NE(Refusal([&] { DecodeTeamTickReply(bytes); }).find("control status 9"),
            std::string::npos);
  // a reply cut short (a field missing) or with bytes after its end
  bytes = EncodeTeamTickReply(SampleTeamTickReply());
  std::vector<uint8_t> cut(bytes.begin(), bytes.end() - 4);
  EXPECT_EQ(Refusal([&] { DecodeTeamTickReply(cut); }),
            "malformed team_tick_reply message: replies count 2, more than the rest of the "
            "message holds");
  bytes.push_back(0);
  EXPECT_NE(Refusal([&] { DecodeTeamTickReply(bytes); }).find("after its end"), std::string::npos);

  // against its team_tick: one reply per view, each the view's vehicle
  replies = SampleTeamTickReply();
  replies[1].vehicle = 1;
  EXPECT_EQ(Refusal([&] { CheckTeamTickReply(replies, tick); }),
            "team_tick_reply refused: reply 1 is for vehicle 1, expected vehicle 2 (the "
            "team_tick's view 1)");
  replies.pop_back();
  EXPECT_EQ(Refusal([&] { CheckTeamTickReply(replies, tick); }),
            "team_tick_reply refused: 1 replies to a team_tick of 2 view(s)");
}

TEST(TeamProtocolTest, TheHelloCarriesTheTeamAndItsReference) {
  const TeamHello hello = SampleHello();
  const TeamHello back = ParseTeamHello(Bytes(TeamHelloToJson(hello)));
  EXPECT_EQ(back.scenario, hello.scenario);
  EXPECT_EQ(back.seed, hello.seed);
  EXPECT_EQ(back.vehicles, hello.vehicles);
  EXPECT_EQ(back.controller, hello.controller);
  EXPECT_EQ(back.team.payload_mass_kg, hello.team.payload_mass_kg);
  EXPECT_EQ(back.team.payload_inertia_P_kgm2, hello.team.payload_inertia_P_kgm2);
  EXPECT_EQ(back.team.gravity_mps2, hello.team.gravity_mps2);
  ASSERT_EQ(back.team.vehicles.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(back.team.vehicles[i].cable_length_m, hello.team.vehicles[i].cable_length_m);
    EXPECT_EQ(back.team.vehicles[i].p_PA_P_m, hello.team.vehicles[i].p_PA_P_m);
    EXPECT_EQ(back.team.vehicles[i].params.quad_mass_kg,
              hello.team.vehicles[i].params.quad_mass_kg);
  }
  // the same reference, bit for bit
  const auto a = MakeReference(hello.reference, hello.team.vehicles[0].params);
  const auto b = MakeReference(back.reference, back.team.vehicles[0].params);
  for (const double t_s : {0.0, 0.5, 1.0 / 3.0 + 2.0, 7.5}) {
    EXPECT_EQ(a->At(t_s).p_WL_W, b->At(t_s).p_WL_W) << t_s;
    EXPECT_EQ(a->At(t_s).v_WL_W, b->At(t_s).v_WL_W) << t_s;
  }

  const nlohmann::json good = TeamHelloToJson(hello);
  nlohmann::json j = good;
  j["vehicles"] = {2};
  EXPECT_EQ(Refusal([&] { ParseTeamHello(Bytes(j)); }),
            "team_hello's vehicles is [2], expected ascending vehicle indices in [0, 2)");
  j = good;
  j["controller"] = "pd";
  EXPECT_EQ(Refusal([&] { ParseTeamHello(Bytes(j)); }),
            "team_hello's controller is \"pd\", a team controller this stack does not have");
  j = good;
  j["team"]["vehicles"][1]["cable_length_m"] = -0.5;
  EXPECT_EQ(Refusal([&] { ParseTeamHello(Bytes(j)); }),
            "team_hello's team's vehicle 1's cable_length_m is -0.5, expected a finite number > 0");
  j = good;
  j["team"].erase("payload_mass_kg");
  EXPECT_EQ(Refusal([&] { ParseTeamHello(Bytes(j)); }), "team_hello's team has no payload_mass_kg");
  j = good;
  j["protocol_version"] = 2;
  EXPECT_NE(Refusal([&] { ParseTeamHello(Bytes(j)); }).find("protocol version 2"),
            std::string::npos);
}

TEST(TeamProtocolTest, TheHelloAckNamesTheStackItsRateAndItsVehicles) {
  const nlohmann::json ack = {{"protocol_version", kProtocolVersion},
                              {"name", "hpa-flight (cooperative)"},
                              {"controller", "cooperative"},
                              {"control_rate_hz", 100.0},
                              {"vehicles", {0, 1}}};
  const TeamHelloAck back = ParseTeamHelloAck(Bytes(ack), {0, 1});
  EXPECT_EQ(back.name, "hpa-flight (cooperative)");
  EXPECT_EQ(back.controller, "cooperative");
  EXPECT_EQ(back.control_rate_hz, 100.0);
  EXPECT_EQ(back.vehicles, (std::vector<int>{0, 1}));

  nlohmann::json j = ack;
  j["vehicles"] = {1};
  EXPECT_EQ(Refusal([&] {
              ParseTeamHelloAck(Bytes(j), {0, 1});
            }),
            "team_hello_ack's vehicles are [1], expected the team_hello's (vehicles 0, 1)");
  j = ack;
  j["control_rate_hz"] = 0;
  EXPECT_EQ(Refusal([&] {
              ParseTeamHelloAck(Bytes(j), {0, 1});
            }),
            "team_hello_ack's control_rate_hz is 0, expected a rate in (0, 1000] Hz");
  j = ack;
  j.erase("control_rate_hz");
  EXPECT_EQ(Refusal([&] {
              ParseTeamHelloAck(Bytes(j), {0, 1});
            }),
            "team_hello_ack has no control_rate_hz");
  j = ack;
  j["batched_ticks"] = true;
  EXPECT_EQ(Refusal([&] {
              ParseTeamHelloAck(Bytes(j), {0, 1});
            }),
            "team_hello_ack's key 'batched_ticks' is not declared in the message table "
            "(messages.json)");
}

}  // namespace
}  // namespace hpa::flight
