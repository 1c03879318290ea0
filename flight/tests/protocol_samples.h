#pragma once
// Sample lockstep messages for the protocol tests: every field of each set away from its
// default, as the golden encodings (protocol_golden.json) record them.

#include <cmath>

#include "hpa/flight/protocol.h"
#include "hpa/flight/team_protocol.h"

namespace hpa::flight {

/// A state with every field away from SystemState's defaults.
inline SystemState SampleState(double time_s) {
  SystemState s;
  s.time_s = time_s;
  s.p_WL_W = {0.1, -0.2, 0.7};
  s.v_WL_W = {1e-17, 2.0, -3.0};
  s.p_WQ_W = {0.25, 0.5, 1.25};
  s.v_WQ_W = {-0.5, 0.125, 1.0 / 3.0};
  s.q_WB = Eigen::Quaterniond(0.3, -0.5, 0.7, 0.1).normalized();
  s.w_B = {0.01, -0.02, M_PI};
  s.mode = CableMode::kSlack;
  s.payload_visible = false;
  s.payload_lost = true;
  s.payload_supported = true;
  return s;
}

/// A tick with every field and flag set, two items in most lists (one of them mostly default).
inline FlightInputs SampleTick() {
  FlightInputs in;
  in.time_s = 1.234;
  in.allocation = AllocationReport{7.891234567890123, true};
  in.need_estimate = true;
  in.gripper_active = true;
  in.no_reply = true;
  in.reference.p_WL_W = {0.1, -0.2, 0.7};
  in.reference.v_WL_W = {1e-17, 2.0, -3.0};
  in.reference.a_WL_W = {-0.0, 9.81, 0.5};
  ImuSample imu;
  imu.time_s = 1.232;
  imu.gyro_B_radps = {0.1, 0.2, M_PI};
  imu.accel_B_mps2 = {0.0, -0.0, 9.81};
  ImuSample imu2 = imu;
  imu2.time_s = 1.233;
  imu2.accel_B_mps2 = {0.5, 0.25, 9.5};
  in.imu = {imu, imu2};
  VioSample vio;
  vio.time_s = 1.2;
  vio.p_WB_W = {1, 2, 3};
  vio.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  vio.v_WB_W = {0.5, -0.5, 0.25};
  in.vio = {vio};
  PayloadDetection d;
  d.time_s = 1.201;
  d.found = true;
  d.reason = "partly out of view \xc3\xa9";
  d.p_CL_C = {0.01, 0.02, 0.5};
  d.centre_px = {320.5, 240.25};
  d.radius_px = 12.75;
  PayloadDetection lost;
  lost.time_s = 1.202;
  lost.reason = "out of view";
  in.detections = {d, lost};
  CameraFrame frame;
  frame.capture_time_s = 1.2;
  frame.region = cv::Rect(10, 20, 30, 40);
  frame.region_slot = 2;
  frame.whole_slot = 3;
  CameraFrame whole;  // no region of interest: its slot stays -1
  whole.capture_time_s = 1.21;
  whole.whole_slot = 0;
  in.frames = {frame, whole};
  in.truth = SampleState(1.234);
  return in;
}

/// A finish: the last step's samples, nothing optional.
inline FlightInputs SampleFinish() {
  FlightInputs in;
  in.time_s = 8.0;
  ImuSample imu;
  imu.time_s = 7.999;
  imu.gyro_B_radps = {0.0, -0.1, 0.2};
  imu.accel_B_mps2 = {0.1, 0.2, 9.7};
  in.imu = {imu};
  in.reference.p_WL_W = {0, 0, 1};
  return in;
}

/// A reply with a command, its estimate, every counter (the health resets by cause too) and a
/// camera region.
inline FlightOutputs SampleReply() {
  FlightOutputs out;
  out.has_command = true;
  out.command.command.w_B_radps = {0.1, -0.2, 0.3};
  out.command.command.thrust_N = 8.123456789;
  out.command.status = ControlStatus::kFallback;
  out.command.solve_time_ms = 0.3125;
  out.command.cost = 12.5;
  out.has_estimate = true;
  out.estimate = SampleState(1.234);
  out.estimator_rejected_updates = 3;
  out.estimator_resets = 2;
  out.frames_detected = 1;
  out.camera_roi = cv::Rect(5, 6, 7, 8);
  out.estimator_health_resets = EstimatorHealthResets{1, 3, 4, 2};
  return out;
}

/// A reply with the estimate alone (a tick that asked for it, no control step).
inline FlightOutputs SampleEstimateReply() {
  FlightOutputs out;
  out.has_estimate = true;
  out.estimate = SampleState(0.5);
  out.estimate.mode = CableMode::kTaut;
  out.estimate.payload_visible = true;
  out.estimate.payload_lost = false;
  out.estimate.payload_supported = false;
  return out;
}

/// A detect of a frame whose region is read out (asking the stack to detect in it).
inline CameraFrame SampleDetect() {
  CameraFrame frame;
  frame.capture_time_s = 2.5;
  frame.region = cv::Rect(100, 80, 64, 48);
  frame.region_slot = 0;
  return frame;
}

/// A detect_reply with the detection found in the frame's region.
inline DetectReply SampleDetectReply() {
  DetectReply reply;
  reply.has_detection = true;
  reply.detection.time_s = 2.5;
  reply.detection.found = true;
  reply.detection.p_CL_C = {-0.03, 0.04, 0.45};
  reply.detection.centre_px = {130.5, 101.75};
  reply.detection.radius_px = 9.5;
  return reply;
}

/// A detect_reply asking for a region of the frame to be read out.
inline DetectReply SampleRegionWantedReply() {
  DetectReply reply;
  reply.region_wanted = true;
  reply.camera_roi = cv::Rect(100, 80, 64, 48);
  return reply;
}

/// A rate_tick with every field away from its default.
inline RateTick SampleRateTick() {
  RateTick tick;
  tick.time_s = 3.001;
  tick.command.w_B_radps = {0.5, -0.25, 0.125};
  tick.command.thrust_N = 7.75;
  tick.w_B_radps = {-0.0, 0.0625, -1.5};
  return tick;
}

/// A rate_reply with every field away from its default.
inline AutopilotOutput SampleRateReply() {
  AutopilotOutput out;
  out.w_cmd_radps << 1000.5, 1100.25, 950.125, 1830.0;
  out.thrust_allocated_N = 6.4921875;
  out.saturated = true;
  return out;
}

/// A team_tick of two vehicles' views, every field away from its default (a negative zero among
/// them).
inline TeamTick SampleTeamTick() {
  TeamTick tick;
  tick.time_s = 2.01;
  for (const int vehicle : {0, 2}) {
    TeamVehicleView& v = tick.views.emplace_back();
    v.vehicle = vehicle;
    v.view.time_s = tick.time_s;
    v.view.p_WQ_W = {0.25 + vehicle, -0.5, 1.5};
    v.view.v_WQ_W = {0.125, -0.0, 1.0 / 3.0};
    v.view.q_WB = Eigen::Quaterniond(0.3, -0.5, 0.7, 0.1).normalized();
    v.view.w_B = {0.01, -0.02, M_PI};
    v.view.p_WL_W = {0.1, -0.2, 0.75};
    v.view.v_WL_W = {1e-17, 2.0, -3.0 - vehicle};
    v.view.q_WP = Eigen::Quaterniond(0.9, 0.1, -0.3, 0.2).normalized();
    v.view.w_P = {-0.125, 0.0625, 0.5};
  }
  return tick;
}

/// A team_tick_reply of two vehicles' replies, every field away from its default.
inline std::vector<TeamVehicleReply> SampleTeamTickReply() {
  std::vector<TeamVehicleReply> replies(2);
  for (int k = 0; k < 2; ++k) {
    TeamVehicleReply& r = replies[static_cast<size_t>(k)];
    r.vehicle = 2 * k;
    r.output.command.w_B_radps = {0.5 + k, -0.25, 0.125};
    r.output.command.thrust_N = 7.75 - k;
    r.output.status = ControlStatus::kFallback;
    r.output.solve_time_ms = 0.375;
    r.output.cost = 12.5;
    r.cable_taut = false;
  }
  return replies;
}

}  // namespace hpa::flight
