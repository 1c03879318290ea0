#pragma once
// The fault event (docs/faults.md): a component of the world fails in a mode for a while. The
// runner reads its window to measure the recovery from it (metrics.json `faults`).

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hpa/scenarios/events.h"
#include "hpa/scenarios/metrics.h"
#include "hpa/sim/faults.h"

namespace hpa {

/// A fault injected into the world at the event's time, for its duration.
struct FaultEvent final : EventAction {
  std::string component, mode;       // as written in the event
  sim::Fault fault;                  // its window is set when it is applied
  std::optional<double> duration_s;  // s (none: to the end of the run; 0: an instant)
  double tracking_bound_m = 0.1;     // the payload error counted as tracking again
  std::optional<int> vehicle;        // the vehicle it hits (`vehicle`; a team's must name it)
  /// The fault with its window from now_s for its duration.
  sim::Fault At(double now_s) const;
  /// Injects the fault from the world's time now for its duration.
  void Apply(sim::World* world) const override;
};

/// Reads a fault event's keys (component, mode, duration, tracking_bound and the mode's own
/// keys from sim::FaultComponents); InputError naming the key and the valid values.
std::shared_ptr<const EventAction> ParseFaultEvent(const YamlMap& map);

/// The windows of the fault events among `events` that start by `end_s`, in time order (each
/// with its index in `events`), for their recovery metrics.
std::vector<FaultWindow> FaultWindows(const std::vector<EventSpec>& events, double end_s);

}  // namespace hpa
