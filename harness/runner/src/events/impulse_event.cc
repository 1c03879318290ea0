// An impulse on the payload or the quadrotor: a constant force over a few physics steps.

#include <cstdio>
#include <string>

#include "hpa/models/params.h"
#include "hpa/models/yaml_reader.h"
#include "event_body.h"
#include "hpa/scenarios/events.h"
#include "hpa/sim/world.h"

namespace hpa {
namespace {

// Largest speed change (m/s) an impulse plausibly gives its body: a hand's push or a gust gives
// a few m/s, while 0.5-3 N s on a 0.05 kg payload would be 10-60 m/s.
constexpr double kPlausibleImpulseSpeed_mps = 10.0;

}  // namespace

ImpulseEvent ImpulseEvent::Parse(const YamlMap& map) {
  ImpulseEvent e;
  e.on_payload = EventActsOnPayload(map);
  e.vehicle = EventVehicle(map);
  e.impulse_W_Ns = map.Vector("impulse", 3, -1e3, 1e3);
  e.duration_s = map.Number("duration", 1e-3, 1.0, 0.01);
  return e;
}

void ImpulseEvent::Apply(sim::World* world) const {
  world->disturbances().ApplyImpulse(EventBody(on_payload), impulse_W_Ns,
                      duration_s);
}

std::string ImpulseEvent::Warning(const Params& world_params) const {
  const double mass_kg = on_payload ? world_params.payload_mass_kg : world_params.quad_mass_kg;
  const double speed_mps = impulse_W_Ns.norm() / mass_kg;
  if (!(speed_mps > kPlausibleImpulseSpeed_mps)) return {};
  char text[256];
  std::snprintf(text, sizeof(text),
                "%.3g N s on the %s (%.3g kg) gives it %.3g m/s, beyond a plausible %.3g m/s",
                impulse_W_Ns.norm(), on_payload ? "payload" : "quadrotor", mass_kg, speed_mps,
                kPlausibleImpulseSpeed_mps);
  return text;
}

}  // namespace hpa
