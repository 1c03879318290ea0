// An impulse on the payload or the quadrotor: a constant force over a few physics steps.

#include "hpa/models/yaml_reader.h"
#include "hpa/scenarios/events.h"
#include "hpa/sim/world.h"

namespace hpa {

ImpulseEvent ImpulseEvent::Parse(const YamlMap& map) {
  ImpulseEvent e;
  e.on_payload = map.Choice("body", {"payload", "quadrotor"}, "payload") == "payload";
  e.impulse_W_Ns = map.Vector("impulse", 3, -1e3, 1e3);
  e.duration_s = map.Number("duration", 1e-3, 1.0, 0.01);
  return e;
}

void ImpulseEvent::Apply(sim::World* world) const {
  world->ApplyImpulse(on_payload ? sim::Body::kPayload : sim::Body::kQuadrotor, impulse_W_Ns,
                      duration_s);
}

}  // namespace hpa
