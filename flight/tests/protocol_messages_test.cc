// Every message type of the lockstep protocol through the C++ encoder and decoder, every field
// set to a value other than its default: what is encoded is what is decoded, the message table
// (python/hpa_sim/messages.json) binds every field, and the encodings equal the committed golden
// ones (flight/tests/protocol_golden.json), which the Python client's test decodes and
// re-encodes too (python/tests/test_protocol_messages.py): both languages agree byte for byte.
//
// A new field: set it in the samples below, then rewrite the golden file's hex with
// HPA_UPDATE_PROTOCOL_GOLDEN=1 flight_test --gtest_filter='ProtocolMessagesTest.*' and its
// values with python3 python/tests/test_protocol_messages.py --update.

#include <gtest/gtest.h>
#include <sys/socket.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "flight/tests/protocol_samples.h"
#include "hpa/flight/protocol.h"

namespace hpa::flight {
namespace {

const std::string kGoldenPath = std::string(HPA_SOURCE_DIR) + "/flight/tests/protocol_golden.json";

void ExpectSameState(const SystemState& a, const SystemState& b) {
  EXPECT_EQ(a.time_s, b.time_s);
  EXPECT_EQ(a.p_WL_W, b.p_WL_W);
  EXPECT_EQ(a.v_WL_W, b.v_WL_W);
  EXPECT_EQ(a.p_WQ_W, b.p_WQ_W);
  EXPECT_EQ(a.v_WQ_W, b.v_WQ_W);
  EXPECT_EQ(a.q_WB.coeffs(), b.q_WB.coeffs());
  EXPECT_EQ(a.w_B, b.w_B);
  EXPECT_EQ(a.mode, b.mode);
  EXPECT_EQ(a.payload_visible, b.payload_visible);
  EXPECT_EQ(a.payload_lost, b.payload_lost);
  EXPECT_EQ(a.payload_supported, b.payload_supported);
}

// Every member of a tick, bit for bit (a negative zero keeps its sign).
void ExpectSameTick(const FlightInputs& a, const FlightInputs& b) {
  EXPECT_EQ(a.time_s, b.time_s);
  ASSERT_EQ(a.allocation.has_value(), b.allocation.has_value());
  if (a.allocation) {
    EXPECT_EQ(a.allocation->thrust_allocated_N, b.allocation->thrust_allocated_N);
    EXPECT_EQ(a.allocation->saturated, b.allocation->saturated);
  }
  EXPECT_EQ(a.need_estimate, b.need_estimate);
  EXPECT_EQ(a.gripper_active, b.gripper_active);
  EXPECT_EQ(a.no_reply, b.no_reply);
  EXPECT_EQ(a.reference.p_WL_W, b.reference.p_WL_W);
  EXPECT_EQ(a.reference.v_WL_W, b.reference.v_WL_W);
  EXPECT_EQ(a.reference.a_WL_W, b.reference.a_WL_W);
  EXPECT_EQ(std::signbit(a.reference.a_WL_W.x()), std::signbit(b.reference.a_WL_W.x()));
  ASSERT_EQ(a.imu.size(), b.imu.size());
  for (size_t i = 0; i < a.imu.size(); ++i) {
    EXPECT_EQ(a.imu[i].time_s, b.imu[i].time_s);
    EXPECT_EQ(a.imu[i].gyro_B_radps, b.imu[i].gyro_B_radps);
    EXPECT_EQ(a.imu[i].accel_B_mps2, b.imu[i].accel_B_mps2);
    EXPECT_EQ(std::signbit(a.imu[i].accel_B_mps2.y()), std::signbit(b.imu[i].accel_B_mps2.y()));
  }
  ASSERT_EQ(a.vio.size(), b.vio.size());
  for (size_t i = 0; i < a.vio.size(); ++i) {
    EXPECT_EQ(a.vio[i].time_s, b.vio[i].time_s);
    EXPECT_EQ(a.vio[i].p_WB_W, b.vio[i].p_WB_W);
    EXPECT_EQ(a.vio[i].q_WB.coeffs(), b.vio[i].q_WB.coeffs());
    EXPECT_EQ(a.vio[i].v_WB_W, b.vio[i].v_WB_W);
  }
  ASSERT_EQ(a.detections.size(), b.detections.size());
  for (size_t i = 0; i < a.detections.size(); ++i) {
    EXPECT_EQ(a.detections[i].time_s, b.detections[i].time_s);
    EXPECT_EQ(a.detections[i].found, b.detections[i].found);
    EXPECT_EQ(a.detections[i].p_CL_C, b.detections[i].p_CL_C);
    EXPECT_EQ(a.detections[i].centre_px, b.detections[i].centre_px);
    EXPECT_EQ(a.detections[i].radius_px, b.detections[i].radius_px);
    EXPECT_EQ(a.detections[i].reason, b.detections[i].reason);
  }
  ASSERT_EQ(a.frames.size(), b.frames.size());
  for (size_t i = 0; i < a.frames.size(); ++i) {
    EXPECT_EQ(a.frames[i].capture_time_s, b.frames[i].capture_time_s);
    EXPECT_EQ(a.frames[i].region, b.frames[i].region);
    EXPECT_EQ(a.frames[i].region_slot, b.frames[i].region_slot);
    EXPECT_EQ(a.frames[i].whole_slot, b.frames[i].whole_slot);
  }
  ASSERT_EQ(a.truth.has_value(), b.truth.has_value());
  if (a.truth) ExpectSameState(*a.truth, *b.truth);
}

// Every member of a reply the protocol carries.
void ExpectSameReply(const FlightOutputs& a, const FlightOutputs& b) {
  ASSERT_EQ(a.has_command, b.has_command);
  if (a.has_command) {
    EXPECT_EQ(a.command.command.w_B_radps, b.command.command.w_B_radps);
    EXPECT_EQ(a.command.command.thrust_N, b.command.command.thrust_N);
    EXPECT_EQ(a.command.status, b.command.status);
    EXPECT_EQ(a.command.solve_time_ms, b.command.solve_time_ms);
    EXPECT_EQ(a.command.cost, b.command.cost);
  }
  ASSERT_EQ(a.has_estimate, b.has_estimate);
  if (a.has_estimate) ExpectSameState(a.estimate, b.estimate);
  EXPECT_EQ(a.estimator_rejected_updates, b.estimator_rejected_updates);
  EXPECT_EQ(a.estimator_resets, b.estimator_resets);
  EXPECT_EQ(a.frames_detected, b.frames_detected);
  EXPECT_EQ(a.camera_roi, b.camera_roi);
}

// Every member of a detect_reply.
void ExpectSameDetectReply(const DetectReply& a, const DetectReply& b) {
  EXPECT_EQ(a.has_detection, b.has_detection);
  EXPECT_EQ(a.region_wanted, b.region_wanted);
  EXPECT_EQ(a.whole_wanted, b.whole_wanted);
  EXPECT_EQ(a.camera_roi, b.camera_roi);
  if (!a.has_detection) return;
  EXPECT_EQ(a.detection.time_s, b.detection.time_s);
  EXPECT_EQ(a.detection.found, b.detection.found);
  EXPECT_EQ(a.detection.p_CL_C, b.detection.p_CL_C);
  EXPECT_EQ(a.detection.centre_px, b.detection.centre_px);
  EXPECT_EQ(a.detection.radius_px, b.detection.radius_px);
  EXPECT_EQ(a.detection.reason, b.detection.reason);
}

std::string Hex(const std::vector<uint8_t>& bytes) {
  std::string out;
  char two[3];
  for (const uint8_t b : bytes) {
    std::snprintf(two, sizeof two, "%02x", b);
    out += two;
  }
  return out;
}

std::vector<uint8_t> Unhex(const std::string& hex) {
  std::vector<uint8_t> out;
  for (size_t i = 0; i + 1 < hex.size(); i += 2) {
    out.push_back(static_cast<uint8_t>(std::stoul(hex.substr(i, 2), nullptr, 16)));
  }
  return out;
}

// The golden samples: name, message type, and the encoding of the C++ sample.
struct Golden {
  std::string name;
  std::string message;
  std::vector<uint8_t> bytes;
};

std::vector<Golden> Encodings() {
  return {{"tick", "tick", EncodeTick(SampleTick())},
          {"finish", "finish", EncodeTick(SampleFinish())},
          {"empty_tick", "tick", EncodeTick(FlightInputs())},
          {"tick_reply", "tick_reply", EncodeReply(SampleReply())},
          {"estimate_reply", "tick_reply", EncodeReply(SampleEstimateReply())},
          {"empty_reply", "tick_reply", EncodeReply(FlightOutputs())},
          {"detect", "detect", EncodeDetect(SampleDetect())},
          {"detect_reply", "detect_reply", EncodeDetectReply(SampleDetectReply())},
          {"region_wanted_reply", "detect_reply", EncodeDetectReply(SampleRegionWantedReply())},
          {"rate_tick", "rate_tick", EncodeRateTick(SampleRateTick())},
          {"rate_reply", "rate_reply", EncodeRateReply(SampleRateReply())},
          {"team_tick", "team_tick", EncodeTeamTick(SampleTeamTick())},
          {"team_tick_reply", "team_tick_reply", EncodeTeamTickReply(SampleTeamTickReply())}};
}

// The table binds every field and bit of every binary message, and declares each field's type
// and doc (and each number's unit): CheckMessageBindings refuses a field no C++ member carries,
// a member bound to a name the table lacks, and a struct no message uses.
TEST(ProtocolMessagesTest, TheTableCoversEveryField) {
  EXPECT_NO_THROW(CheckMessageBindings());
  const nlohmann::json& table = MessageTable();
  EXPECT_EQ(table.at("protocol_version"), kProtocolVersion);
  EXPECT_EQ(table.at("magic"), kMagic);
  EXPECT_EQ(table.at("max_message_bytes"), kMaxMessageBytes);
  for (const nlohmann::json& type : table.at("message_types")) {
    EXPECT_EQ(MessageTypeName(static_cast<MessageType>(type.at("id").get<uint32_t>())),
              type.at("name"));
  }
  for (const auto& item : table.at("structs").items()) {
    for (const nlohmann::json& f : item.value().at("fields")) {
      const std::string where = item.key() + "." + f.at("name").get<std::string>();
      EXPECT_TRUE(f.contains("doc")) << where;
      if (f.at("type") == "f64") EXPECT_TRUE(f.contains("unit")) << where;
    }
  }
}

// Every message type through encode and decode: each field comes back with every bit. The JSON
// messages (hello_ack, finish_reply) through their parsers, the error message through a channel.
TEST(ProtocolMessagesTest, EveryMessageTypeRoundTrips) {
  for (const FlightInputs& in : {SampleTick(), SampleFinish(), FlightInputs()}) {
    ExpectSameTick(DecodeTick(EncodeTick(in)), in);
  }
  for (const FlightOutputs& out : {SampleReply(), SampleEstimateReply(), FlightOutputs()}) {
    ExpectSameReply(DecodeReply(EncodeReply(out)), out);
  }

  const CameraFrame frame = DecodeDetect(EncodeDetect(SampleDetect()));
  EXPECT_EQ(frame.capture_time_s, SampleDetect().capture_time_s);
  EXPECT_EQ(frame.region, SampleDetect().region);
  EXPECT_EQ(frame.region_slot, SampleDetect().region_slot);
  EXPECT_EQ(frame.whole_slot, SampleDetect().whole_slot);
  for (const DetectReply& r : {SampleDetectReply(), SampleRegionWantedReply()}) {
    ExpectSameDetectReply(DecodeDetectReply(EncodeDetectReply(r)), r);
  }
  const RateTick rate_tick = DecodeRateTick(EncodeRateTick(SampleRateTick()));
  EXPECT_EQ(rate_tick.time_s, SampleRateTick().time_s);
  EXPECT_EQ(rate_tick.command.w_B_radps, SampleRateTick().command.w_B_radps);
  EXPECT_EQ(rate_tick.command.thrust_N, SampleRateTick().command.thrust_N);
  EXPECT_EQ(rate_tick.w_B_radps, SampleRateTick().w_B_radps);
  EXPECT_TRUE(std::signbit(rate_tick.w_B_radps.x()));
  const AutopilotOutput rate_reply = DecodeRateReply(EncodeRateReply(SampleRateReply()));
  EXPECT_EQ(rate_reply.w_cmd_radps, SampleRateReply().w_cmd_radps);
  EXPECT_EQ(rate_reply.thrust_allocated_N, SampleRateReply().thrust_allocated_N);
  EXPECT_EQ(rate_reply.saturated, SampleRateReply().saturated);

  // exactly one of a detect_reply's flags
  DetectReply none;
  EXPECT_THROW(DecodeDetectReply(EncodeDetectReply(none)), ProtocolError);
  DetectReply two = SampleDetectReply();
  two.whole_wanted = true;
  EXPECT_THROW(DecodeDetectReply(EncodeDetectReply(two)), ProtocolError);

  const nlohmann::json ack = {{"protocol_version", kProtocolVersion},
                              {"name", "sample stack"},
                              {"controller", "pd"},
                              {"control_rate_hz", 125.5},
                              {"batched_ticks", true},
                              {"detects_at_capture", true},
                              {"owns_rate_loop", true}};
  const std::string ack_text = ack.dump();
  const HelloAck back = ParseHelloAck(std::vector<uint8_t>(ack_text.begin(), ack_text.end()));
  EXPECT_EQ(back.name, "sample stack");
  EXPECT_EQ(back.controller, "pd");
  EXPECT_EQ(back.control_rate_hz, 125.5);
  EXPECT_TRUE(back.batched_ticks);
  EXPECT_TRUE(back.detects_at_capture);
  EXPECT_TRUE(back.owns_rate_loop);

  const nlohmann::json finish = {
      {"estimator", "hybrid"},
      {"estimator_health", nlohmann::json::array({nlohmann::json::array({"resets", 2}),
                                                  nlohmann::json::array({"innovation_m", 0.25})})},
      {"frames_detected", 3}};
  const std::string finish_text = finish.dump();
  const FinishReply reply =
      ParseFinishReply(std::vector<uint8_t>(finish_text.begin(), finish_text.end()), 4);
  EXPECT_EQ(reply.estimator, "hybrid");
  ASSERT_EQ(reply.estimator_health.size(), 2u);
  EXPECT_EQ(reply.estimator_health[1], std::make_pair(std::string("innovation_m"), 0.25));
  EXPECT_EQ(reply.frames_detected, 3);

  int fds[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_STREAM, 0, fds), 0);
  Channel a(fds[0]), b(fds[1]);
  const std::string text = "stopped: \xc3\xa9";
  a.Send(MessageType::kError, std::vector<uint8_t>(text.begin(), text.end()));
  std::vector<uint8_t> body;
  try {
    b.Receive(&body, 1.0);
    FAIL() << "an error message was not thrown";
  } catch (const ProtocolError& e) {
    EXPECT_EQ(std::string(e.what()), "the peer reported: " + text);
  }
}

// The JSON messages' keys are the table's too: what a side sends is checked against them (an
// undeclared key, a missing required one, a value of another JSON type), nested objects included.
TEST(ProtocolMessagesTest, JsonMessagesAreCheckedAgainstTheTablesKeys) {
  const nlohmann::json ack = {{"protocol_version", kProtocolVersion}, {"name", "s"},
                              {"controller", "pd"}, {"control_rate_hz", 100},
                              {"batched_ticks", true}, {"detects_at_capture", false}};
  EXPECT_NO_THROW(CheckJsonMessage(MessageType::kHelloAck, ack));
  const auto error = [](MessageType type, const nlohmann::json& j) {
    try {
      CheckJsonMessage(type, j);
    } catch (const ProtocolError& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  nlohmann::json extra = ack;
  extra["rate_hz"] = 1;
  EXPECT_EQ(error(MessageType::kHelloAck, extra),
            "hello_ack's key 'rate_hz' is not declared in the message table (messages.json)");
  nlohmann::json typed = ack;
  typed["batched_ticks"] = 1;
  EXPECT_EQ(error(MessageType::kHelloAck, typed), "hello_ack's batched_ticks is 1, expected a bool");
  EXPECT_EQ(error(MessageType::kHelloAck, {{"name", "s"}}), "hello_ack has no protocol_version");
  const nlohmann::json hello = {
      {"protocol_version", kProtocolVersion}, {"scenario", "hover"}, {"seed", 1},
      {"rates", nlohmann::json::array()}, {"config", nlohmann::json::object()},
      {"camera", {{"ring", "/r"}, {"slots", 6}, {"width_px", 4}, {"height_px", 2},
                  {"slot_bytes", 24}}}};
  EXPECT_NO_THROW(CheckJsonMessage(MessageType::kHello, hello));
  nlohmann::json no_slots = hello;
  no_slots["camera"].erase("slots");
  EXPECT_EQ(error(MessageType::kHello, no_slots), "hello's camera has no slots");
  EXPECT_NO_THROW(CheckJsonMessage(
      MessageType::kFinishReply,
      {{"estimator", "hybrid"}, {"estimator_health", nlohmann::json::array()},
       {"frames_detected", 0}}));
  EXPECT_THROW(CheckJsonMessage(MessageType::kTick, nlohmann::json::object()), ProtocolError);
}

// The encodings are the committed golden ones (the Python client's test checks the same
// bytes); with HPA_UPDATE_PROTOCOL_GOLDEN set, the test rewrites their hex instead.
TEST(ProtocolMessagesTest, EncodingsEqualTheGoldenFile) {
  nlohmann::json golden;
  {
    std::ifstream file(kGoldenPath);
    ASSERT_TRUE(file) << kGoldenPath;
    file >> golden;
  }
  std::map<std::string, nlohmann::json*> by_name;
  for (nlohmann::json& entry : golden.at("messages")) by_name[entry.at("name")] = &entry;
  if (std::getenv("HPA_UPDATE_PROTOCOL_GOLDEN") != nullptr) {
    nlohmann::json messages = nlohmann::json::array();
    for (const Golden& g : Encodings()) {
      nlohmann::json entry = by_name.count(g.name) ? *by_name[g.name] : nlohmann::json::object();
      entry["name"] = g.name;
      entry["message"] = g.message;
      entry["hex"] = Hex(g.bytes);
      messages.push_back(entry);
    }
    golden["messages"] = messages;
    std::ofstream(kGoldenPath) << golden.dump(2) << "\n";
    GTEST_SKIP() << "rewrote " << kGoldenPath;
  }
  for (const Golden& g : Encodings()) {
    ASSERT_EQ(by_name.count(g.name), 1u) << g.name << " is not in " << kGoldenPath;
    const nlohmann::json& entry = *by_name[g.name];
    EXPECT_EQ(entry.at("message"), g.message) << g.name;
    EXPECT_EQ(entry.at("hex").get<std::string>(), Hex(g.bytes)) << g.name;
    // and the golden bytes decode to what encodes to them
    const std::vector<uint8_t> bytes = Unhex(entry.at("hex").get<std::string>());
    if (g.message == "tick_reply") {
      EXPECT_EQ(EncodeReply(DecodeReply(bytes)), bytes) << g.name;
    } else if (g.message == "detect") {
      EXPECT_EQ(EncodeDetect(DecodeDetect(bytes)), bytes) << g.name;
    } else if (g.message == "detect_reply") {
      EXPECT_EQ(EncodeDetectReply(DecodeDetectReply(bytes)), bytes) << g.name;
    } else if (g.message == "rate_tick") {
      EXPECT_EQ(EncodeRateTick(DecodeRateTick(bytes)), bytes) << g.name;
    } else if (g.message == "rate_reply") {
      EXPECT_EQ(EncodeRateReply(DecodeRateReply(bytes)), bytes) << g.name;
    } else if (g.message == "team_tick") {
      EXPECT_EQ(EncodeTeamTick(DecodeTeamTick(bytes)), bytes) << g.name;
    } else if (g.message == "team_tick_reply") {
      EXPECT_EQ(EncodeTeamTickReply(DecodeTeamTickReply(bytes)), bytes) << g.name;
    } else {
      EXPECT_EQ(EncodeTick(DecodeTick(bytes)), bytes) << g.name;
    }
  }
}

}  // namespace
}  // namespace hpa::flight
