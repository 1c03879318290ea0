// The tick, the finish and the tick_reply (docs/protocol.md): the codecs of the structs they
// carry, bound member by member to the message table, their encoding and decoding, and the check
// of a decoded reply against the tick it answers.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "hpa/flight/protocol.h"
#include "message_codecs.h"
#include "message_table.h"
#include "protocol_common.h"

namespace hpa::flight {
namespace {

using wire::Bind;
using wire::BindBit;
using wire::Codec;

// Each struct that crosses the wire, bound member by member to its struct of the message table
// (python/hpa_sim/messages.json): the table declares the fields' order, types, units and checks,
// these bindings say which member holds each.

const Codec<SystemState>& StateCodec() {
  static const Codec<SystemState> codec(
      "state", {Bind("time_s", &SystemState::time_s), Bind("p_WL_W", &SystemState::p_WL_W),
                Bind("v_WL_W", &SystemState::v_WL_W), Bind("p_WQ_W", &SystemState::p_WQ_W),
                Bind("v_WQ_W", &SystemState::v_WQ_W), Bind("q_WB", &SystemState::q_WB),
                Bind("w_B", &SystemState::w_B), Bind("mode", &SystemState::mode),
                BindBit("payload_visible", &SystemState::payload_visible),
                BindBit("payload_lost", &SystemState::payload_lost),
                BindBit("payload_supported", &SystemState::payload_supported)});
  return codec;
}

const Codec<ReferenceSample>& ReferenceCodec() {
  static const Codec<ReferenceSample> codec(
      "reference_sample",
      {Bind("p_WL_W", &ReferenceSample::p_WL_W), Bind("v_WL_W", &ReferenceSample::v_WL_W),
       Bind("a_WL_W", &ReferenceSample::a_WL_W)});
  return codec;
}

const Codec<AllocationReport>& AllocationCodec() {
  static const Codec<AllocationReport> codec(
      "allocation_report", {Bind("thrust_allocated_N", &AllocationReport::thrust_allocated_N)});
  return codec;
}

const Codec<EstimatorHealthResets>& HealthResetsCodec() {
  static const Codec<EstimatorHealthResets> codec(
      "health_resets", {Bind("quad_non_finite", &EstimatorHealthResets::quad_non_finite),
                        Bind("payload_non_finite", &EstimatorHealthResets::payload_non_finite),
                        Bind("payload_speed", &EstimatorHealthResets::payload_speed),
                        Bind("cable_length", &EstimatorHealthResets::cable_length)});
  return codec;
}

const Codec<ImuSample>& ImuCodec() {
  static const Codec<ImuSample> codec(
      "imu_sample",
      {Bind("time_s", &ImuSample::time_s), Bind("gyro_B_radps", &ImuSample::gyro_B_radps),
       Bind("accel_B_mps2", &ImuSample::accel_B_mps2)});
  return codec;
}

const Codec<VioSample>& VioCodec() {
  static const Codec<VioSample> codec(
      "vio_sample", {Bind("time_s", &VioSample::time_s), Bind("p_WB_W", &VioSample::p_WB_W),
                     Bind("q_WB", &VioSample::q_WB), Bind("v_WB_W", &VioSample::v_WB_W)});
  return codec;
}

}  // namespace

const Codec<PayloadDetection>& DetectionCodec() {
  static const Codec<PayloadDetection> codec(
      "payload_detection",
      {Bind("time_s", &PayloadDetection::time_s), Bind("found", &PayloadDetection::found),
       Bind("p_CL_C", &PayloadDetection::p_CL_C), Bind("centre_px", &PayloadDetection::centre_px),
       Bind("radius_px", &PayloadDetection::radius_px), Bind("reason", &PayloadDetection::reason)});
  return codec;
}

const Codec<CameraFrame>& FrameCodec() {
  static const Codec<CameraFrame> codec(
      "camera_frame",
      {Bind("capture_time_s", &CameraFrame::capture_time_s), Bind("region", &CameraFrame::region),
       Bind("region_slot", &CameraFrame::region_slot),
       Bind("whole_slot", &CameraFrame::whole_slot)});
  return codec;
}

const Codec<FlightInputs>& TickCodec() {
  static const Codec<FlightInputs> codec(
      "tick",
      {Bind("time_s", &FlightInputs::time_s),
       // the mixer's saturation travels as a flag beside the allocation it belongs to
       BindBit<FlightInputs>(
           "saturated",
           [](const FlightInputs& in) { return in.allocation && in.allocation->saturated; },
           [](FlightInputs& in, bool v) {
             if (in.allocation) in.allocation->saturated = v;
           }),
       BindBit("need_estimate", &FlightInputs::need_estimate),
       BindBit("gripper_active", &FlightInputs::gripper_active),
       BindBit("no_reply", &FlightInputs::no_reply),
       Bind("allocation", &FlightInputs::allocation, AllocationCodec()),
       Bind("reference", &FlightInputs::reference, ReferenceCodec()),
       Bind("imu", &FlightInputs::imu, ImuCodec()), Bind("vio", &FlightInputs::vio, VioCodec()),
       Bind("detections", &FlightInputs::detections, DetectionCodec()),
       Bind("frames", &FlightInputs::frames, FrameCodec()),
       Bind("truth", &FlightInputs::truth, StateCodec())});
  return codec;
}

const Codec<FlightOutputs>& ReplyCodec() {
  static const Codec<FlightOutputs> codec(
      "tick_reply",
      {Bind("command", &FlightOutputs::command, ControlOutputCodec(), &FlightOutputs::has_command),
       Bind("estimate", &FlightOutputs::estimate, StateCodec(), &FlightOutputs::has_estimate),
       Bind("rejected_updates", &FlightOutputs::estimator_rejected_updates),
       Bind("resets", &FlightOutputs::estimator_resets),
       Bind("frames_detected", &FlightOutputs::frames_detected),
       Bind("camera_roi", &FlightOutputs::camera_roi),
       Bind("health_resets", &FlightOutputs::estimator_health_resets, HealthResetsCodec())});
  return codec;
}

std::vector<uint8_t> EncodeTick(const FlightInputs& in) { return EncodeBody(TickCodec(), in); }

FlightInputs DecodeTick(const std::vector<uint8_t>& body) {
  return DecodeBody(TickCodec(), body, "tick");
}

std::vector<uint8_t> EncodeReply(const FlightOutputs& out) { return EncodeBody(ReplyCodec(), out); }

FlightOutputs DecodeReply(const std::vector<uint8_t>& body) {
  return DecodeBody(ReplyCodec(), body, "tick_reply");
}

void CheckReply(const FlightOutputs& out, const ReplyBounds& bounds) {
  const auto fail = [](const std::string& what) {
    throw ProtocolError("tick_reply refused: " + what);
  };
  if (static_cast<size_t>(out.frames_detected) > bounds.frames) {
    fail("frames_detected " + std::to_string(out.frames_detected) + ", but the tick delivered " +
         std::to_string(bounds.frames) + " frame(s)");
  }
  // each counted update, and each health-check re-initialisation (made at an update), was made
  // with a message the stack received
  std::vector<std::pair<std::string, int>> counts = {
      {"rejected_updates", out.estimator_rejected_updates}, {"resets", out.estimator_resets}};
  if (out.estimator_health_resets) {
    const EstimatorHealthResets& r = *out.estimator_health_resets;
    counts.insert(counts.end(), {{"health_resets.quad_non_finite", r.quad_non_finite},
                                 {"health_resets.payload_non_finite", r.payload_non_finite},
                                 {"health_resets.payload_speed", r.payload_speed},
                                 {"health_resets.cable_length", r.cable_length}});
  }
  for (const auto& [name, v] : counts) {
    if (static_cast<uint64_t>(v) > bounds.messages_so_far) {
      fail(std::string(name) + " " + std::to_string(v) + ", more than the " +
           std::to_string(bounds.messages_so_far) + " sensor messages delivered so far");
    }
  }
  if (bounds.estimate_needed && !out.has_estimate) {
    fail("no estimate, but the tick asked for one (flag 8, estimate needed)");
  }
  if (out.has_command && !out.has_estimate) {
    fail("a command without the estimate it was computed from");
  }
  const cv::Rect& roi = out.camera_roi;
  if (roi.width < 0 || roi.height < 0) {
    fail("camera_roi of size " + std::to_string(roi.width) + " x " + std::to_string(roi.height));
  }
  if (bounds.image_width_px > 0 && roi.area() > 0 &&
      (roi.x < 0 || roi.y < 0 || roi.x > bounds.image_width_px - roi.width ||
       roi.y > bounds.image_height_px - roi.height)) {
    fail("camera_roi (" + std::to_string(roi.x) + ", " + std::to_string(roi.y) + ", " +
         std::to_string(roi.width) + ", " + std::to_string(roi.height) + ") outside the " +
         std::to_string(bounds.image_width_px) + " x " + std::to_string(bounds.image_height_px) +
         " image");
  }
}

}  // namespace hpa::flight
