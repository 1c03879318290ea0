#include "hpa/models/input_error.h"
#include "hpa/models/yaml_reader.h"
#include "hpa/scenarios/events.h"

namespace hpa {
namespace {

template <typename Event>
EventAction Parse(const YamlMap& map) {
  return Event::Parse(map);
}

}  // namespace

const std::vector<EventRegistration>& EventTypes() {
  // one line per event type
  static const std::vector<EventRegistration> types = {
      {"gripper_grab", "the gripper takes the payload where it is", Parse<GripperGrabEvent>},
      {"gripper_move", "moves the gripper to `to` over `duration` s", Parse<GripperMoveEvent>},
      {"gripper_release", "the gripper lets the payload go", Parse<GripperReleaseEvent>},
      {"impulse", "`impulse` N s on the `body` (payload | quadrotor)", Parse<ImpulseEvent>},
      {"wind", "`force` N on the quadrotor for `duration` s", Parse<WindEvent>},
  };
  return types;
}

EventSpec ParseEvent(const YamlMap& map) {
  EventSpec event;
  event.at_s = map.Number("at", 0.0, 1e5);
  std::vector<std::string> names;
  for (const EventRegistration& r : EventTypes()) names.push_back(r.name);
  event.type = map.Choice("type", names, "");
  for (const EventRegistration& r : EventTypes()) {
    if (r.name == event.type) event.action = r.parse(map);
  }
  map.RejectUnknownKeys();
  return event;
}

void ApplyEvent(const EventSpec& event, sim::World* world) {
  std::visit([world](const auto& action) { action.Apply(world); }, event.action);
}

}  // namespace hpa
