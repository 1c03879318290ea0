#pragma once
// The body an event pushes (`body: payload | quadrotor`), read the same way by every event type.

#include "hpa/models/yaml_reader.h"
#include "hpa/sim/world.h"

namespace hpa {

/// Whether the event's `body` key names the payload (the default) rather than the quadrotor.
inline bool EventActsOnPayload(const YamlMap& map) {
  return map.Choice("body", {"payload", "quadrotor"}, "payload") == "payload";
}

/// The vehicle a quadrotor event acts on in a team scenario (`vehicle`, from 0; a single-vehicle
/// scenario refuses any but 0).
inline int EventVehicle(const YamlMap& map) { return static_cast<int>(map.Integer("vehicle", 0, 2, 0)); }

/// The world's body an event acts on.
inline sim::Body EventBody(bool on_payload) {
  return on_payload ? sim::Body::kPayload : sim::Body::kQuadrotor;
}

}  // namespace hpa
