#include "hpa/flight/protocol.h"

#include <gtest/gtest.h>
#include <sys/socket.h>

#include <cmath>
#include <cstring>
#include <limits>

namespace hpa::flight {
namespace {

FlightInputs SampleInputs() {
  FlightInputs in;
  in.time_s = 1.234;
  in.allocation = AllocationReport{7.891234567890123, true};
  in.need_estimate = true;
  in.gripper_active = true;
  in.reference.p_WL_W = {0.1, -0.2, 0.7};
  in.reference.v_WL_W = {1e-17, 2.0, -3.0};
  ImuSample imu;
  imu.time_s = 1.232;
  imu.gyro_B_radps = {0.1, 0.2, M_PI};
  imu.accel_B_mps2 = {0.0, -0.0, 9.81};
  in.imu = {imu, imu};
  VioSample vio;
  vio.time_s = 1.2;
  vio.p_WB_W = {1, 2, 3};
  vio.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  in.vio = {vio};
  PayloadDetection d;
  d.time_s = 1.201;
  d.found = false;
  d.reason = "partly out of view";
  d.p_CL_C = {0.01, 0.02, 0.5};
  in.detections = {d};
  CameraFrame frame;
  frame.capture_time_s = 1.2;
  frame.region = cv::Rect(10, 20, 30, 40);
  frame.region_slot = 2;
  frame.whole_slot = 3;
  in.frames = {frame};
  SystemState truth;
  truth.p_WQ_W = {0, 0, 1.2};
  truth.mode = CableMode::kSlack;
  truth.payload_lost = true;
  in.truth = truth;
  return in;
}

// Every number crosses the wire with all its bits: the in-process and the out-of-process flight
// stack see the same inputs.
TEST(ProtocolTest, TickRoundTripsBitForBit) {
  const FlightInputs in = SampleInputs();
  const FlightInputs out = DecodeTick(EncodeTick(in));
  EXPECT_EQ(out.time_s, in.time_s);
  ASSERT_TRUE(out.allocation.has_value());
  EXPECT_EQ(out.allocation->thrust_allocated_N, in.allocation->thrust_allocated_N);
  EXPECT_TRUE(out.allocation->saturated);
  EXPECT_TRUE(out.need_estimate);
  EXPECT_TRUE(out.gripper_active);
  EXPECT_EQ(out.reference.v_WL_W, in.reference.v_WL_W);
  ASSERT_EQ(out.imu.size(), 2u);
  EXPECT_EQ(out.imu[1].gyro_B_radps, in.imu[1].gyro_B_radps);
  EXPECT_TRUE(std::signbit(out.imu[0].accel_B_mps2.y()));
  ASSERT_EQ(out.vio.size(), 1u);
  EXPECT_EQ(out.vio[0].q_WB.coeffs(), in.vio[0].q_WB.coeffs());
  ASSERT_EQ(out.detections.size(), 1u);
  EXPECT_EQ(out.detections[0].reason, "partly out of view");
  EXPECT_FALSE(out.detections[0].found);
  EXPECT_EQ(out.detections[0].p_CL_C, in.detections[0].p_CL_C);
  ASSERT_EQ(out.frames.size(), 1u);
  EXPECT_EQ(out.frames[0].whole_slot, 3);
  EXPECT_EQ(out.frames[0].region_slot, 2);
  EXPECT_EQ(out.frames[0].region, cv::Rect(10, 20, 30, 40));
  EXPECT_EQ(out.frames[0].capture_time_s, 1.2);
  ASSERT_TRUE(out.truth.has_value());
  EXPECT_EQ(out.truth->p_WQ_W, in.truth->p_WQ_W);
  EXPECT_EQ(out.truth->mode, CableMode::kSlack);
  EXPECT_TRUE(out.truth->payload_lost);
}

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
  std::vector<uint8_t> tick = EncodeTick(SampleInputs());
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
  c.controller.type = "geometric";
  c.controller.perception_weight = 0.1 + 0.2;
  c.controller.qp_method = "riccati";
  c.reference.type = "line";
  c.reference.line_end_W_m = {1.0 / 3.0, 0, 0.7};
  c.estimate_latency_s = 0.002;
  c.initial_state.p_WQ_W = {0, 0, 1.2};
  const FlightConfig back = ConfigFromJson(nlohmann::json::parse(ConfigToJson(c).dump()));
  EXPECT_EQ(back.params.cable_length_m, 0.7);
  EXPECT_EQ(back.params.R_BC, c.params.R_BC);
  EXPECT_EQ(back.controller.type, "geometric");
  EXPECT_EQ(back.controller.perception_weight, c.controller.perception_weight);
  EXPECT_EQ(back.controller.qp_method, "riccati");
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

}  // namespace
}  // namespace hpa::flight
