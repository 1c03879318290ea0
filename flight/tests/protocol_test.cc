#include "hpa/flight/protocol.h"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <thread>

#include "flight/tests/protocol_samples.h"

namespace hpa::flight {
namespace {

// The smallest detection (found, no reason) as the tick's last message: the count check must
// accept exactly its size.
TEST(ProtocolTest, ATickWithOnlyADetectionDecodes) {
  FlightInputs in;
  PayloadDetection d;
  d.found = true;
  d.p_CL_C = {0.0, 0.1, 0.5};
  in.detections = {d};
  const FlightInputs out = DecodeTick(EncodeTick(in));
  ASSERT_EQ(out.detections.size(), 1u);
  EXPECT_TRUE(out.detections[0].found);
  EXPECT_EQ(out.detections[0].p_CL_C, d.p_CL_C);
}

TEST(ProtocolTest, ReplyRoundTripsAndRefusesNonFiniteCommands) {
  FlightOutputs out;
  out.has_command = true;
  out.command.command.w_B_radps = {0.1, -0.2, 0.3};
  out.command.command.thrust_N = 8.123456789;
  out.command.status = ControlStatus::kFallback;
  out.has_estimate = true;
  out.estimate.p_WL_W = {1, 2, 3};
  out.estimator_resets = 2;
  out.frames_detected = 1;
  out.camera_roi = cv::Rect(5, 6, 7, 8);
  const FlightOutputs back = DecodeReply(EncodeReply(out));
  EXPECT_EQ(back.command.command.thrust_N, out.command.command.thrust_N);
  EXPECT_EQ(back.command.status, ControlStatus::kFallback);
  EXPECT_EQ(back.estimate.p_WL_W, out.estimate.p_WL_W);
  EXPECT_EQ(back.estimator_resets, 2);
  EXPECT_EQ(back.frames_detected, 1);
  EXPECT_EQ(back.camera_roi, out.camera_roi);

  out.command.command.thrust_N = std::numeric_limits<double>::quiet_NaN();
  try {
    DecodeReply(EncodeReply(out));
    FAIL() << "a NaN thrust was accepted";
  } catch (const ProtocolError& e) {
    EXPECT_NE(std::string(e.what()).find("non-finite command"), std::string::npos) << e.what();
  }
}

TEST(ProtocolTest, MalformedMessagesAreRefusedNamingWhy) {
  std::vector<uint8_t> tick = EncodeTick(SampleTick());
  std::vector<uint8_t> cut(tick.begin(), tick.begin() + tick.size() / 2);
  EXPECT_THROW(DecodeTick(cut), ProtocolError);
  std::vector<uint8_t> longer = tick;
  longer.push_back(0);
  try {
    DecodeTick(longer);
    FAIL() << "trailing bytes were accepted";
  } catch (const ProtocolError& e) {
    EXPECT_NE(std::string(e.what()).find("1 bytes after its end"), std::string::npos) << e.what();
  }
  // an IMU count far beyond what the message holds is refused before anything is allocated
  std::vector<uint8_t> huge = EncodeTick(FlightInputs());
  const size_t imu_count_at = 8 + 4 + 9 * 8;
  const uint32_t n = 0x7fffffff;
  std::memcpy(huge.data() + imu_count_at, &n, 4);
  EXPECT_THROW(DecodeTick(huge), ProtocolError);
}

TEST(ProtocolTest, ConfigRoundTripsThroughJson) {
  FlightConfig c;
  c.params.cable_length_m = 0.7;
  c.params.R_BC(0, 1) = 0.25;
  c.controller.type = "hpa_mpc";
  c.controller.settings["perception_weight"] = 0.1 + 0.2;
  c.controller.settings["qp_method"] = std::string("riccati");
  c.reference.type = "line";
  c.reference.line_end_W_m = {1.0 / 3.0, 0, 0.7};
  c.estimate_latency_s = 0.002;
  c.initial_state.p_WQ_W = {0, 0, 1.2};
  const FlightConfig back = ConfigFromJson(nlohmann::json::parse(ConfigToJson(c).dump()));
  EXPECT_EQ(back.params.cable_length_m, 0.7);
  EXPECT_EQ(back.params.R_BC, c.params.R_BC);
  EXPECT_EQ(back.controller.type, "hpa_mpc");
  EXPECT_EQ(back.controller.Number("perception_weight"), 0.1 + 0.2);
  EXPECT_EQ(back.controller.Name("qp_method"), "riccati");
  EXPECT_EQ(back.reference.line_end_W_m, c.reference.line_end_W_m);
  EXPECT_EQ(back.initial_state.p_WQ_W, c.initial_state.p_WQ_W);
  nlohmann::json missing = ConfigToJson(c);
  missing["params"].erase("cable_length_m");
  try {
    ConfigFromJson(missing);
    FAIL() << "a config without cable_length_m was accepted";
  } catch (const ProtocolError& e) {
    EXPECT_NE(std::string(e.what()).find("cable_length_m"), std::string::npos) << e.what();
  }
}

// A peer that is not an hpa lockstep peer, and one that goes silent, are errors, not hangs.
TEST(ProtocolTest, ChannelRefusesAForeignPeerAndTimesOut) {
  int fds[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_STREAM, 0, fds), 0);
  Channel a(fds[0]), b(fds[1]);
  std::vector<uint8_t> body;
  EXPECT_THROW(b.Receive(&body, 0.05), ProtocolError);  // nothing sent: times out
  const char junk[12] = "GET / HTTP";
  ASSERT_EQ(::send(fds[0], junk, sizeof junk, 0), static_cast<ssize_t>(sizeof junk));
  try {
    b.Receive(&body, 1.0);
    FAIL() << "a foreign peer was accepted";
  } catch (const ProtocolError& e) {
    EXPECT_NE(std::string(e.what()).find("magic"), std::string::npos) << e.what();
  }
  a.Send(MessageType::kError, {'b', 'o', 'o', 'm'});
  try {
    b.Receive(&body, 1.0);
    FAIL();
  } catch (const ProtocolError& e) {
    EXPECT_NE(std::string(e.what()).find("boom"), std::string::npos) << e.what();
  }
}

// The text a peer sends may be any bytes; what enters JSON must be UTF-8: valid text crosses
// unchanged, each ill-formed part becomes U+FFFD.
TEST(ProtocolTest, CleanUtf8KeepsValidTextAndReplacesTheRest) {
  const std::string valid = "hover \xc3\xa9\xe2\x82\xac \xf0\x9f\x9a\x81 ok";
  EXPECT_EQ(CleanUtf8(valid), valid);
  EXPECT_EQ(CleanUtf8("bad \xff\xfe end"), "bad \xef\xbf\xbd\xef\xbf\xbd end");
  EXPECT_EQ(CleanUtf8("cut \xc3"), "cut \xef\xbf\xbd");          // ends mid-sequence
  EXPECT_EQ(CleanUtf8("\xc0\xaf"), "\xef\xbf\xbd\xef\xbf\xbd");  // overlong '/'
  EXPECT_EQ(CleanUtf8("\xed\xa0\x80"), "\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd");  // surrogate
  EXPECT_EQ(CleanUtf8("\xf4\x90\x80\x80").substr(0, 3), "\xef\xbf\xbd");         // past U+10FFFF
  EXPECT_EQ(CleanUtf8("\xe2\x82("), "\xef\xbf\xbd(");  // a cut sequence, then text
  // whatever comes out dumps as JSON
  for (int b = 0; b < 256; ++b) {
    const std::string text = CleanUtf8(std::string(1, static_cast<char>(b)) + "\x80\xbf");
    EXPECT_NO_THROW(nlohmann::json(text).dump()) << b;
  }
}

namespace {

// A reply that passes every check: a command with its estimate.
FlightOutputs GoodReply() {
  FlightOutputs out;
  out.has_command = true;
  out.command.command.thrust_N = 8.0;
  out.command.solve_time_ms = 0.3;
  out.command.cost = 12.5;
  out.has_estimate = true;
  return out;
}

// The ProtocolError text `f` throws ("" when it does not throw).
template <class F>
std::string ErrorOf(F&& f) {
  try {
    f();
  } catch (const ProtocolError& e) {
    return e.what();
  }
  return "";
}

// Whether `text` contains `part`.
bool Has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

// A reply's command and estimate: every refusal names the field and the value.
TEST(ProtocolTest, ReplyValuesOutsideTheirDefinitionAreRefused) {
  EXPECT_EQ(ErrorOf([] { DecodeReply(EncodeReply(GoodReply())); }), "");
  FlightOutputs out = GoodReply();
  out.command.solve_time_ms = -1e9;
  EXPECT_TRUE(Has(ErrorOf([&] { DecodeReply(EncodeReply(out)); }), "solve time -1000000000 ms"));
  out = GoodReply();
  out.command.solve_time_ms = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(Has(ErrorOf([&] { DecodeReply(EncodeReply(out)); }), "solve time inf"));
  out = GoodReply();
  out.command.cost = -4e302;
  EXPECT_TRUE(
      Has(ErrorOf([&] { DecodeReply(EncodeReply(out)); }), "cost -4.0000000000000003e+302"));
  out.command.cost = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(Has(ErrorOf([&] { DecodeReply(EncodeReply(out)); }), "cost nan"));
  out = GoodReply();
  out.estimate.q_WB = Eigen::Quaterniond(0, 0, 0, 0);
  EXPECT_TRUE(Has(ErrorOf([&] { DecodeReply(EncodeReply(out)); }), "quaternion q_WB of norm 0"));
  out.estimate.q_WB = Eigen::Quaterniond(2, 0, 0, 0);
  EXPECT_TRUE(Has(ErrorOf([&] { DecodeReply(EncodeReply(out)); }), "of norm 2,"));
}

// A stack that owns the rate loop: a non-finite rotor speed or allocated thrust is refused where
// it is decoded, a speed outside the motors' range by CheckRateReply, each naming the value.
TEST(ProtocolTest, RateRepliesOutsideTheirDefinitionAreRefused) {
  const Params params;
  AutopilotOutput out;
  out.w_cmd_radps.setConstant(0.5 * (params.motor_speed_min_radps + params.motor_speed_max_radps));
  out.thrust_allocated_N = 7.0;
  EXPECT_EQ(ErrorOf([&] { CheckRateReply(DecodeRateReply(EncodeRateReply(out)), params); }), "");
  AutopilotOutput bad = out;
  bad.w_cmd_radps[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(Has(ErrorOf([&] { DecodeRateReply(EncodeRateReply(bad)); }),
                  "a non-finite rotor speed command nan rad/s"));
  bad = out;
  bad.thrust_allocated_N = -1.0;
  EXPECT_TRUE(Has(ErrorOf([&] { DecodeRateReply(EncodeRateReply(bad)); }),
                  "thrust allocated -1 N, expected a finite number >= 0"));
  bad = out;
  bad.w_cmd_radps[1] = 5000.0;
  // params.h's motor range: 100 to 1830 rad/s
  EXPECT_EQ(ErrorOf([&] { CheckRateReply(bad, params); }),
            "rate_reply refused: rotor 1 speed command 5000 rad/s, outside the motors' range "
            "[100, 1830] rad/s");
  bad.w_cmd_radps[1] = 0.0;
  EXPECT_TRUE(Has(ErrorOf([&] { CheckRateReply(bad, params); }), "rotor 1 speed command 0 rad/s"));
}

// The hello's rate_loop carries the world profile's rate loop to a stack that owns it, every bit.
TEST(ProtocolTest, RateLoopConfigRoundTripsThroughJson) {
  RateLoopConfig c;
  c.spec.px4 = true;
  c.spec.params.p = {0.125, 0.15, 0.2 / 3.0};
  c.spec.params.gyro_cutoff_hz = 41.5;
  c.own_rate_hz = 500.0;
  const RateLoopConfig back = RateLoopFromJson(nlohmann::json::parse(RateLoopToJson(c).dump()));
  EXPECT_TRUE(back.spec.px4);
  EXPECT_EQ(back.own_rate_hz, 500.0);
  EXPECT_EQ(back.spec.params.p, c.spec.params.p);
  EXPECT_EQ(back.spec.params.gyro_cutoff_hz, 41.5);
  EXPECT_EQ(back.spec.params.rate_hz, c.spec.params.rate_hz);
  nlohmann::json j = RateLoopToJson(c);
  j["own_rate_hz"] = 0.0;
  EXPECT_TRUE(Has(ErrorOf([&] { RateLoopFromJson(j); }), "rate_loop.own_rate_hz"));
  j = RateLoopToJson(c);
  j["params"].erase("gyro_cutoff_hz");
  EXPECT_TRUE(Has(ErrorOf([&] { RateLoopFromJson(j); }), "bad rate_loop in the hello"));
}

// Within [0.9, 1.1] a quaternion is renormalised; a unit one (to rounding) keeps every bit, so
// the separate stack's estimate equals the in-process one.
TEST(ProtocolTest, NearUnitQuaternionsAreRenormalisedAndUnitOnesKeptExactly) {
  FlightOutputs out = GoodReply();
  out.estimate.q_WB = Eigen::Quaterniond(1.05, 0, 0, 0);
  EXPECT_EQ(DecodeReply(EncodeReply(out)).estimate.q_WB.w(), 1.0);
  out.estimate.q_WB = Eigen::Quaterniond(0.3, -0.5, 0.7, 0.1).normalized();
  const Eigen::Quaterniond back = DecodeReply(EncodeReply(out)).estimate.q_WB;
  EXPECT_EQ(back.coeffs(), out.estimate.q_WB.coeffs());
}

// Counters are unsigned on the wire: one past INT_MAX would read as a negative count.
TEST(ProtocolTest, CountersPastInt32AreRefused) {
  FlightOutputs out = GoodReply();
  std::vector<uint8_t> body = EncodeReply(out);
  const uint32_t max = 0xFFFFFFFFu;
  std::memcpy(body.data() + body.size() - 16 - 12, &max, 4);  // rejected_updates
  EXPECT_TRUE(Has(ErrorOf([&] { DecodeReply(body); }), "rejected_updates 4294967295"));
  // an estimate's state flags with unknown bits
  body = EncodeReply(out);
  const uint32_t flags = 8;
  std::memcpy(body.data() + body.size() - 16 - 12 - 4, &flags, 4);
  EXPECT_TRUE(Has(ErrorOf([&] { DecodeReply(body); }), "estimate flags 0x8 with unknown bits"));
}

// A reply checked against its tick: detections within the frames delivered, counters within the
// messages delivered, the estimate asked for, a camera region inside the image.
TEST(ProtocolTest, RepliesAreCheckedAgainstTheirTick) {
  ReplyBounds bounds;
  bounds.frames = 2;
  bounds.estimate_needed = true;
  bounds.messages_so_far = 16;
  bounds.image_width_px = 640;
  bounds.image_height_px = 480;
  FlightOutputs out = GoodReply();
  out.frames_detected = 2;
  out.estimator_rejected_updates = 16;
  out.camera_roi = cv::Rect(600, 400, 40, 80);
  EXPECT_EQ(ErrorOf([&] { CheckReply(out, bounds); }), "");
  FlightOutputs bad = out;
  bad.frames_detected = 1000;
  EXPECT_TRUE(Has(ErrorOf([&] { CheckReply(bad, bounds); }),
                  "frames_detected 1000, but the tick delivered 2 frame(s)"));
  bad = out;
  bad.estimator_resets = 17;
  EXPECT_TRUE(Has(ErrorOf([&] { CheckReply(bad, bounds); }), "resets 17, more than the 16"));
  bad = out;
  bad.estimator_health_resets = EstimatorHealthResets{0, 0, 16, 0};
  EXPECT_EQ(ErrorOf([&] { CheckReply(bad, bounds); }), "");
  bad.estimator_health_resets->cable_length = 17;
  EXPECT_TRUE(Has(ErrorOf([&] { CheckReply(bad, bounds); }),
                  "health_resets.cable_length 17, more than the 16"));
  bad.estimator_health_resets->cable_length = -1;
  EXPECT_TRUE(Has(ErrorOf([&] { CheckReply(bad, bounds); }), "health_resets.cable_length -1"));
  bad = out;
  bad.has_command = false;
  bad.has_estimate = false;
  EXPECT_TRUE(Has(ErrorOf([&] { CheckReply(bad, bounds); }), "no estimate, but the tick asked"));
  bounds.estimate_needed = false;
  EXPECT_EQ(ErrorOf([&] { CheckReply(bad, bounds); }), "");  // nothing asked, nothing commanded
  bad.has_command = true;
  EXPECT_TRUE(Has(ErrorOf([&] { CheckReply(bad, bounds); }), "a command without the estimate"));
  bad = out;
  bad.camera_roi = cv::Rect(601, 400, 40, 80);
  EXPECT_TRUE(Has(ErrorOf([&] { CheckReply(bad, bounds); }), "outside the 640 x 480 image"));
  bad.camera_roi = cv::Rect(0, 0, -5, 10);
  EXPECT_TRUE(Has(ErrorOf([&] { CheckReply(bad, bounds); }), "camera_roi of size -5 x 10"));
}

// The version is the integer 1, not a number that rounds or wraps to it.
TEST(ProtocolTest, HelloAckIsRefusedNamingTheFieldAndValue) {
  const auto ack = [](const std::string& text) {
    return ParseHelloAck(std::vector<uint8_t>(text.begin(), text.end()));
  };
  const HelloAck good = ack(R"({"protocol_version": 1, "name": "mine", "control_rate_hz": 100})");
  EXPECT_EQ(good.name, "mine");
  EXPECT_EQ(good.control_rate_hz, 100.0);
  EXPECT_EQ(ack(R"({"protocol_version": 1})").name, "external");
  // the controller it flies: optional (then its name labels the run), a string like the name
  EXPECT_EQ(good.controller, "");
  EXPECT_EQ(ack(R"({"protocol_version": 1, "name": "a", "controller": "pd"})").controller, "pd");
  EXPECT_TRUE(Has(ErrorOf([&] { ack(R"({"protocol_version": 1, "controller": [1]})"); }),
                  "controller is [1]"));
  EXPECT_TRUE(Has(ErrorOf([&] { ack(R"({"protocol_version": 1.9})"); }), "version 1.9,"));
  EXPECT_TRUE(
      Has(ErrorOf([&] { ack(R"({"protocol_version": 4294967297})"); }), "version 4294967297,"));
  EXPECT_TRUE(Has(ErrorOf([&] { ack(R"({"protocol_version": "1"})"); }), "version \"1\""));
  EXPECT_TRUE(Has(ErrorOf([&] { ack(R"({"name": "x"})"); }), "version null"));
  EXPECT_TRUE(Has(ErrorOf([&] { ack(R"({"protocol_version": 1, "name": 7})"); }), "name is 7"));
  EXPECT_TRUE(Has(ErrorOf([&] { ack(R"({"protocol_version": 1, "control_rate_hz": -1})"); }),
                  "control_rate_hz is -1"));
  EXPECT_TRUE(Has(ErrorOf([&] { ack("[1]"); }), "expected a JSON object"));
  // batched ticks follow a declared control rate within the tick clock's
  EXPECT_FALSE(good.batched_ticks);
  EXPECT_FALSE(good.detects_at_capture);
  EXPECT_TRUE(ack(R"({"protocol_version": 1, "control_rate_hz": 150, "batched_ticks": true})")
                  .batched_ticks);
  EXPECT_TRUE(Has(ErrorOf([&] { ack(R"({"protocol_version": 1, "batched_ticks": true})"); }),
                  "batched_ticks needs the control rate"));
  EXPECT_TRUE(Has(
      ErrorOf([&] {
        ack(R"({"protocol_version": 1, "control_rate_hz": 2000, "batched_ticks": true})");
      }),
      "expected a rate in (0, 1000] Hz"));
  // the keys and their types are the message table's: a misspelt flag is not silently off
  EXPECT_TRUE(Has(ErrorOf([&] { ack(R"({"protocol_version": 1, "detects_at_capture": 1})"); }),
                  "hello_ack's detects_at_capture is 1, expected a bool"));
  EXPECT_TRUE(Has(ErrorOf([&] { ack(R"({"protocol_version": 1, "detect_at_capture": true})"); }),
                  "hello_ack's key 'detect_at_capture' is not declared in the message table"));
  // bytes that are not UTF-8 are a malformed message, and the error text is UTF-8 again
  const std::string bad_name =
      ErrorOf([&] { ack("{\"protocol_version\": 1, \"name\": \"a\xff\"}"); });
  EXPECT_TRUE(Has(bad_name, "malformed hello_ack")) << bad_name;
  EXPECT_NO_THROW(nlohmann::json(CleanUtf8(bad_name)).dump());
}

// The finish's counts are integers within what the finish carried; health names cannot take
// the keys metrics.json's estimator block reserves.
TEST(ProtocolTest, FinishReplyIsRefusedNamingTheFieldAndValue) {
  const auto finish = [](const std::string& text, size_t frames) {
    return ParseFinishReply(std::vector<uint8_t>(text.begin(), text.end()), frames);
  };
  const FinishReply good = finish(
      R"({"estimator": "hybrid", "estimator_health": [["resets", 2], ["slack", 0.5]],
          "frames_detected": 3})",
      3);
  EXPECT_EQ(good.estimator, "hybrid");
  ASSERT_EQ(good.estimator_health.size(), 2u);
  EXPECT_EQ(good.estimator_health[1].second, 0.5);
  EXPECT_EQ(good.frames_detected, 3);
  EXPECT_TRUE(Has(ErrorOf([&] { finish(R"({"frames_detected": 1e300})", 3); }),
                  "frames_detected is 1e+300, expected an integer"));
  EXPECT_TRUE(Has(ErrorOf([&] { finish(R"({"frames_found": 3})", 3); }),
                  "finish_reply's key 'frames_found' is not declared"));
  EXPECT_TRUE(Has(ErrorOf([&] { finish(R"({"frames_detected": -5})", 3); }), "is -5"));
  EXPECT_TRUE(Has(ErrorOf([&] { finish(R"({"frames_detected": 4})", 3); }), "is 4"));
  EXPECT_TRUE(Has(ErrorOf([&] { finish(R"({"estimator_health": [["variant", 3]]})", 0); }),
                  "named 'variant', a key metrics.json's estimator block reserves"));
  EXPECT_TRUE(Has(ErrorOf([&] { finish(R"({"estimator_health": [["a", 1], ["a", 2]]})", 0); }),
                  "repeats the name 'a'"));
  EXPECT_TRUE(
      Has(ErrorOf([&] { finish(R"({"estimator_health": [["a b", 1]]})", 0); }), "named \"a b\""));
  EXPECT_TRUE(Has(ErrorOf([&] { finish(R"({"estimator_health": [["a", null]]})", 0); }),
                  "entry 0 is [\"a\",null], expected [name, finite number]"));
  // JSON has no infinity: a number past a double's range is a malformed message
  EXPECT_TRUE(Has(ErrorOf([&] { finish(R"({"estimator_health": [["a", 1e400]]})", 0); }), "1e400"));
  EXPECT_TRUE(
      Has(ErrorOf([&] { finish(R"({"estimator_health": 5})", 0); }), "estimator_health is 5"));
  EXPECT_TRUE(Has(ErrorOf([&] { finish(R"({"estimator": ["x"]})", 0); }), "estimator is"));
}

// One deadline for the whole message: a peer that sends the header in time and the body late is
// as late as one that sends nothing (here: header at 0.3 s, body at 0.6 s, limit 0.45 s).
TEST(ProtocolTest, TheTimeLimitBoundsTheWholeMessage) {
  int fds[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_STREAM, 0, fds), 0);
  Channel a(fds[0]), b(fds[1]);
  const std::vector<uint8_t> body = EncodeReply(GoodReply());
  std::thread peer([&] {
    const uint32_t header[3] = {kMagic, static_cast<uint32_t>(MessageType::kTickReply),
                                static_cast<uint32_t>(body.size())};
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    ASSERT_EQ(::send(fds[0], header, sizeof header, 0), 12);
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    ::send(fds[0], body.data(), body.size(), MSG_NOSIGNAL);
  });
  const auto start = std::chrono::steady_clock::now();
  std::vector<uint8_t> got;
  const std::string error = ErrorOf([&] { b.Receive(&got, 0.45); });
  const double waited_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  peer.join();
  EXPECT_TRUE(Has(error, "no answer within 0.45")) << error;
  EXPECT_TRUE(Has(error, "12 of the message's")) << error;
  // ended at the limit, before the body came (scheduling slack of 0.1 s)
  EXPECT_LT(waited_s, 0.55);
  EXPECT_GE(waited_s, 0.44);
}

// A stop ends a wait within a poll slice (kStopPollS), for a receipt and for a send the peer
// does not read.
TEST(ProtocolTest, AStopEndsAWaitWithinAPollSlice) {
  int fds[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_STREAM, 0, fds), 0);
  Channel a(fds[0]), b(fds[1]);
  std::atomic<bool> stop{false};
  const WaitLimit limit{600.0, [&] { return stop.load(); }};
  for (const bool sending : {false, true}) {
    stop = false;
    // made before the clock starts: filling 64 MB on a loaded machine is not the wait measured
    std::vector<uint8_t> body(sending ? 64 << 20 : 0);
    std::thread signal([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      stop = true;
    });
    const auto start = std::chrono::steady_clock::now();
    try {
      if (sending) {
        a.Send(MessageType::kTick, body, limit);  // far more than the socket buffers
      } else {
        b.Receive(&body, limit);
      }
      ADD_FAILURE() << "the wait did not end";
    } catch (const WaitInterrupted&) {
    }
    signal.join();
    const double waited_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    // 0.2 s until the stop, at most one slice after it (and 0.1 s of scheduling slack)
    EXPECT_LT(waited_s, 0.2 + kStopPollS + 0.1) << (sending ? "send" : "receive");
  }
}

}  // namespace
}  // namespace hpa::flight
