// A fault of a sensor or an actuator for a while (docs/faults.md): `component` and `mode` from
// the world's fault declaration (sim::FaultComponents), the mode's keys read from the same table.

#include "harness/runner/src/events/fault_event.h"

#include <algorithm>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "event_body.h"
#include "hpa/models/yaml_reader.h"
#include "hpa/sim/world.h"

namespace hpa {

sim::Fault FaultEvent::At(double now_s) const {
  sim::Fault f = fault;
  f.start_s = now_s;
  f.end_s = f.start_s + duration_s.value_or(std::numeric_limits<double>::infinity());
  return f;
}

void FaultEvent::Apply(sim::World* world) const { world->faults().Inject(At(world->time_s())); }

/// Reads a fault event's keys (component, mode, duration and the mode's own keys).
std::shared_ptr<const EventAction> ParseFaultEvent(const YamlMap& map) {
  const std::vector<sim::FaultComponentDecl>& components = sim::FaultComponents();
  std::vector<std::string> component_names;
  for (const sim::FaultComponentDecl& c : components) component_names.push_back(c.name);
  const std::string component = map.Choice("component", component_names, "");
  const sim::FaultComponentDecl* c = nullptr;
  for (const sim::FaultComponentDecl& candidate : components) {
    if (candidate.name == component) c = &candidate;
  }
  std::vector<std::string> mode_names;
  for (const sim::FaultModeDecl& m : c->modes) mode_names.push_back(m.name);
  const std::string mode = map.Choice("mode", mode_names, "");
  const sim::FaultModeDecl* m = nullptr;
  for (const sim::FaultModeDecl& candidate : c->modes) {
    if (candidate.name == mode) m = &candidate;
  }

  auto event = std::make_shared<FaultEvent>();
  event->component = component;
  event->mode = mode;
  event->fault.component = c->component;
  event->fault.mode = m->mode;
  if (m->has_duration) {
    if (map.Has("duration")) event->duration_s = map.Number("duration", 0.0, 1e5);
  } else {
    event->duration_s = 0.0;
  }
  event->tracking_bound_m = map.Number("tracking_bound", 0.001, 10.0, 0.1);
  event->vehicle = EventVehicle(map);
  for (const sim::FaultKeyDecl& k : m->keys) {
    if (k.number != nullptr) {
      double value = 0.0;
      if (k.integer) {
        value = k.fallback ? static_cast<double>(map.Integer(k.key, static_cast<long>(k.min),
                                                             static_cast<long>(k.max),
                                                             static_cast<long>(*k.fallback)))
                           : static_cast<double>(map.Integer(k.key, static_cast<long>(k.min),
                                                             static_cast<long>(k.max)));
      } else {
        value = k.fallback ? map.Number(k.key, k.min, k.max, *k.fallback)
                           : map.Number(k.key, k.min, k.max);
      }
      event->fault.*(k.number) = value;
    } else if (k.vector != nullptr) {
      Eigen::Vector3d value = Eigen::Vector3d::Constant(k.fallback.value_or(0.0));
      if (map.Has(k.key) || !k.fallback) value = map.Vector(k.key, 3, k.min, k.max);
      event->fault.*(k.vector) = value;
    }
  }
  return event;
}

std::vector<FaultWindow> FaultWindows(const std::vector<EventSpec>& events, double end_s) {
  std::vector<FaultWindow> windows;
  for (size_t i = 0; i < events.size(); ++i) {
    const auto* fault = dynamic_cast<const FaultEvent*>(events[i].action.get());
    if (fault == nullptr || events[i].at_s > end_s + 1e-9) continue;
    FaultWindow w;
    w.event = static_cast<int>(i);
    w.component = fault->component;
    w.mode = fault->mode;
    w.start_s = events[i].at_s;
    if (fault->duration_s) w.end_s = events[i].at_s + *fault->duration_s;
    w.tracking_bound_m = fault->tracking_bound_m;
    w.vehicle = fault->vehicle.value_or(0);
    windows.push_back(w);
  }
  std::stable_sort(windows.begin(), windows.end(), [](const FaultWindow& a, const FaultWindow& b) {
    return a.start_s < b.start_s;
  });
  return windows;
}

}  // namespace hpa
