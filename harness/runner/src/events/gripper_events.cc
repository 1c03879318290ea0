// The gripper: grab, move, release (a mocap body welded to the payload while it holds it).

#include "hpa/models/yaml_reader.h"
#include "hpa/scenarios/events.h"
#include "hpa/sim/world.h"

namespace hpa {

GripperGrabEvent GripperGrabEvent::Parse(const YamlMap&) { return {}; }

void GripperGrabEvent::Apply(sim::World* world) const { world->gripper().Grab(); }

GripperMoveEvent GripperMoveEvent::Parse(const YamlMap& map) {
  GripperMoveEvent e;
  e.to_W_m = map.Vector("to", 3, -1e3, 1e3);
  e.duration_s = map.Number("duration", 0.0, 1e4);
  return e;
}

void GripperMoveEvent::Apply(sim::World* world) const { world->gripper().Move(to_W_m, duration_s); }

GripperReleaseEvent GripperReleaseEvent::Parse(const YamlMap&) { return {}; }

void GripperReleaseEvent::Apply(sim::World* world) const { world->gripper().Release(); }

}  // namespace hpa
