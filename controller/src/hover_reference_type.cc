// The hover reference type: a constant payload position.

#include "hpa/controller/reference_types.h"

namespace hpa {

/// The hover reference type's keys and behaviour (registered in reference_types.cc).
ReferenceType HoverReferenceType() {
  return {"hover",
          "a constant payload position",
          {{"payload_position", "m", 3, -kReferencePositionBound_m, kReferencePositionBound_m,
            std::nullopt, "the payload's set-point (world)"}},
          [](const ReferenceKeyValues& v, ReferenceSpec* spec) {
            spec->payload_position_W_m = v.Vector3("payload_position");
          },
          // a set-point is flown from the start
          [](const ReferenceSpec&) { return 0.0; },
          [](const ReferenceSpec& spec, const Params& params) {
            return MakeHoverReference(params, spec.payload_position_W_m);
          }};
}

}  // namespace hpa
