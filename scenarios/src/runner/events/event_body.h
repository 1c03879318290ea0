#pragma once
// The body an event pushes (`body: payload | quadrotor`), read the same way by every event type.

#include <optional>

#include "hpa/models/cooperative_model.h"
#include "hpa/models/yaml_reader.h"
#include "hpa/sim/world.h"

namespace hpa {

/// Whether the event's `body` key names the payload (the default) rather than the quadrotor.
inline bool EventActsOnPayload(const YamlMap& map) {
  return map.Choice("body", {"payload", "quadrotor"}, "payload") == "payload";
}

/// The vehicle a quadrotor event acts on (`vehicle`, from 0; unset when the event does not name
/// one). The scenario reader requires it on a team's quadrotor events and refuses it on a
/// payload's, and an index past the scenario's vehicles.
inline std::optional<int> EventVehicle(const YamlMap& map) {
  if (!map.Has("vehicle")) return std::nullopt;
  return static_cast<int>(map.Integer("vehicle", 0, kMaxTeamVehicles - 1, 0));
}

/// The world's body an event acts on.
inline sim::Body EventBody(bool on_payload) {
  return on_payload ? sim::Body::kPayload : sim::Body::kQuadrotor;
}

}  // namespace hpa
