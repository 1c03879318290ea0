// A velocity change of the payload or the quadrotor: dv added to its velocity at once.

#include <cmath>

#include "hpa/models/yaml_reader.h"
#include "event_body.h"
#include "hpa/scenarios/events.h"
#include "hpa/sim/world.h"

namespace hpa {
namespace {

// Largest velocity change (m/s) per component: half the 40 m/s bound on a reference's speed
// (kMaxTrajectorySpeed_mps, the arena's reach); a larger change is a typo, not a disturbance.
constexpr double kMaxVelocityChange_mps = 20.0;

}  // namespace

VelocityChangeEvent VelocityChangeEvent::Parse(const YamlMap& map) {
  VelocityChangeEvent e;
  e.on_payload = EventActsOnPayload(map);
  e.vehicle = EventVehicle(map);
  e.dv_W_mps = map.Vector("dv", 3, -kMaxVelocityChange_mps, kMaxVelocityChange_mps);
  return e;
}

void VelocityChangeEvent::Apply(sim::World* world) const {
  world->disturbances().AddVelocity(EventBody(on_payload), dv_W_mps);
}

}  // namespace hpa
