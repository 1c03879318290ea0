#pragma once
// The body an event pushes (`body: payload | quadrotor`), read the same way by every event type.

#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include "hpa/models/input_error.h"
#include "hpa/models/yaml_reader.h"
#include "hpa/sim/world.h"

namespace hpa {

/// Whether the event's `body` key names the payload (the default) rather than the quadrotor.
inline bool EventActsOnPayload(const YamlMap& map) {
  return map.Choice("body", {"payload", "quadrotor"}, "payload") == "payload";
}

/// The vehicle a quadrotor event acts on (`vehicle`, a whole number from 0; unset when the event
/// does not name one). The scenario reader requires it on a team's quadrotor events, refuses it
/// on a payload's, and refuses an index past the scenario's vehicles naming how many it flies
/// (CheckEventVehicles), so any whole number from 0 is read here.
inline std::optional<int> EventVehicle(const YamlMap& map) {
  if (!map.Has("vehicle")) return std::nullopt;
  double vehicle = -1.0;
  try {
    vehicle = map.Number("vehicle", 0.0, std::numeric_limits<int>::max());
  } catch (const InputError&) {
    vehicle = -1.0;  // not a number, or a negative one: refused below with what an index is
  }
  if (!(vehicle >= 0.0) || vehicle != std::floor(vehicle)) {
    map.Fail("vehicle", "expected a vehicle index, a whole number counted from 0, not " +
                            YAML::Dump(map.Node("vehicle")));
  }
  return static_cast<int>(vehicle);
}

/// The world's body an event acts on.
inline sim::Body EventBody(bool on_payload) {
  return on_payload ? sim::Body::kPayload : sim::Body::kQuadrotor;
}

}  // namespace hpa
