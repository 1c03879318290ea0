// The detect message and its detect_reply (docs/protocol.md): a frame being captured, sent to a
// stack that detects at capture, and its answer (a detection, or the region or the whole frame
// to read out), with the reply's codec and the check that it sets exactly one of its flags.

#include <cstdint>
#include <string>
#include <vector>

#include "hpa/flight/protocol.h"
#include "message_codecs.h"
#include "message_table.h"

namespace hpa::flight {

using wire::Bind;
using wire::BindBit;
using wire::Codec;

const Codec<DetectReply>& DetectReplyCodec() {
  static const Codec<DetectReply> codec(
      "detect_reply",
      {BindBit("region_wanted", &DetectReply::region_wanted),
       BindBit("whole_wanted", &DetectReply::whole_wanted),
       Bind("camera_roi", &DetectReply::camera_roi),
       Bind("detection", &DetectReply::detection, DetectionCodec(), &DetectReply::has_detection)});
  return codec;
}

std::vector<uint8_t> EncodeDetect(const CameraFrame& frame) {
  return EncodeBody(FrameCodec(), frame);
}

CameraFrame DecodeDetect(const std::vector<uint8_t>& body) {
  return DecodeBody(FrameCodec(), body, "detect");
}

std::vector<uint8_t> EncodeDetectReply(const DetectReply& reply) {
  return EncodeBody(DetectReplyCodec(), reply);
}

DetectReply DecodeDetectReply(const std::vector<uint8_t>& body) {
  const DetectReply reply = DecodeBody(DetectReplyCodec(), body, "detect_reply");
  const int set =
      (reply.has_detection ? 1 : 0) + (reply.region_wanted ? 1 : 0) + (reply.whole_wanted ? 1 : 0);
  if (set != 1) {
    throw ProtocolError("detect_reply refused: " + std::to_string(set) +
                        " of its flags set (detection, region wanted, whole frame wanted), "
                        "expected exactly one");
  }
  return reply;
}

}  // namespace hpa::flight
