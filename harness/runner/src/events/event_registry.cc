#include <utility>

#include "hpa/models/input_error.h"
#include "hpa/models/registry.h"
#include "hpa/models/yaml_reader.h"
#include "hpa/scenarios/events.h"
#include "harness/runner/src/events/fault_event.h"

namespace hpa {
namespace {

template <typename Event>
std::shared_ptr<const EventAction> Parse(const YamlMap& map) {
  return std::make_shared<const Event>(Event::Parse(map));
}

Registry<EventRegistration>& TheRegistry() {
  // one line per event type
  static Registry<EventRegistration> registry(
      "event type",
      {
          {"gripper_grab", "the gripper takes the payload where it is", Parse<GripperGrabEvent>},
          {"gripper_move", "moves the gripper to `to` over `duration` s", Parse<GripperMoveEvent>},
          {"gripper_release", "the gripper lets the payload go", Parse<GripperReleaseEvent>},
          {"impulse", "`impulse` N s on the `body` (payload | quadrotor)", Parse<ImpulseEvent>},
          {"velocity_change", "adds `dv` m/s at once to the `body` (payload or quadrotor)",
           Parse<VelocityChangeEvent>},
          {"wind", "`force` N on the quadrotor for `duration` s", Parse<WindEvent>},
          {"fault",
           "a `component` fails in a `mode` for `duration` s (docs/faults.md; `hpa schema "
           "faults`)",
           ParseFaultEvent},
      });
  return registry;
}

}  // namespace

const std::vector<EventRegistration>& EventTypes() { return TheRegistry().All(); }

void RegisterEventType(EventRegistration registration) {
  TheRegistry().Add(std::move(registration));
}

EventSpec ParseEvent(const YamlMap& map) {
  EventSpec event;
  event.at_s = map.Number("at", 0.0, 1e5);
  event.type = map.Choice("type", TheRegistry().Names(), "");
  if (const EventRegistration* registration = TheRegistry().Find(event.type)) {
    event.action = registration->parse(map);
  }
  map.RejectUnknownKeys();
  return event;
}

void ApplyEvent(const EventSpec& event, sim::World* world) {
  if (event.action) event.action->Apply(world);
}

}  // namespace hpa
