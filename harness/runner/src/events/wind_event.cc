// Wind for a while: a constant force on the quadrotor, or a wind velocity that acts through drag.

#include "hpa/models/yaml_reader.h"
#include "hpa/scenarios/events.h"
#include "hpa/sim/world.h"

namespace hpa {

WindEvent WindEvent::Parse(const YamlMap& map) {
  WindEvent e;
  if (map.Has("force") == map.Has("velocity")) {
    map.Fail("force", "give either force (N on the quadrotor) or velocity (m/s of wind)");
  }
  if (map.Has("force")) e.force_W_N = map.Vector("force", 3, -1e3, 1e3);
  if (map.Has("velocity")) e.velocity_W_mps = map.Vector("velocity", 3, -50.0, 50.0);
  e.duration_s = map.Number("duration", 0.0, 1e5);
  return e;
}

void WindEvent::Apply(sim::World* world) const {
  if (velocity_W_mps) {
    world->disturbances().SetWindVelocity(*velocity_W_mps, duration_s);
  } else {
    world->disturbances().SetWind(force_W_N, duration_s);
  }
}

}  // namespace hpa
