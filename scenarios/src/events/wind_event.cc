// Wind: a constant force on the quadrotor for a while.

#include "hpa/models/yaml_reader.h"
#include "hpa/scenarios/events.h"
#include "hpa/sim/world.h"

namespace hpa {

WindEvent WindEvent::Parse(const YamlMap& map) {
  WindEvent e;
  e.force_W_N = map.Vector("force", 3, -1e3, 1e3);
  e.duration_s = map.Number("duration", 0.0, 1e5);
  return e;
}

void WindEvent::Apply(sim::World* world) const { world->SetWind(force_W_N, duration_s); }

}  // namespace hpa
