// Which vehicle each event of a scenario acts on (event_vehicles.h).

#include "harness/runner/src/events/event_vehicles.h"

#include <algorithm>
#include <optional>
#include <string>

#include "hpa/models/input_error.h"
#include "hpa/models/yaml_reader.h"
#include "harness/runner/src/events/fault_event.h"

namespace hpa {
namespace {

// The vehicle an event names (`vehicle`), and whether it acts on the payload.
struct EventTarget {
  std::optional<int> vehicle;
  bool on_payload = false;
};

// What a push, a velocity change or a fault names; nothing for the other types.
EventTarget TargetOf(const EventAction* action) {
  if (const auto* impulse = dynamic_cast<const ImpulseEvent*>(action)) {
    return {impulse->vehicle, impulse->on_payload};
  }
  if (const auto* velocity = dynamic_cast<const VelocityChangeEvent*>(action)) {
    return {velocity->vehicle, velocity->on_payload};
  }
  if (const auto* fault = dynamic_cast<const FaultEvent*>(action)) return {fault->vehicle, false};
  return {};
}

// Refuses what a team's world cannot do: an event other than a push, a velocity change or a
// fault of a component its vehicles carry (a team has no gripper and no payload camera; its
// vehicles' IMU, VIO and rate gyro fly only when they estimate their own state on board).
void CheckTeamEventType(const EventSpec& event, const std::string& path, bool onboard_sensors,
                        const YamlMap& root) {
  const EventAction* action = event.action.get();
  const auto* fault = dynamic_cast<const FaultEvent*>(action);
  const sim::FaultComponent component =
      fault != nullptr ? fault->fault.component : sim::FaultComponent::kMotor;
  const bool sensor = component == sim::FaultComponent::kVio ||
                      component == sim::FaultComponent::kImu ||
                      component == sim::FaultComponent::kRateGyro;
  if (sensor && !onboard_sensors) {
    throw InputError(root.file(), path + ".component",
                     "a team vehicle carries its IMU, VIO and rate gyro when it estimates its own "
                     "state on board (estimation.vehicle_state: onboard); on motion capture or "
                     "the truth a '" +
                         fault->component + "' fault would act on nothing");
  }
  if (fault != nullptr && !sensor && component != sim::FaultComponent::kMotor) {
    throw InputError(root.file(), path + ".component",
                     "a team's vehicles have no gripper and no payload camera: a '" +
                         fault->component + "' fault would act on nothing");
  }
  if (fault == nullptr && dynamic_cast<const ImpulseEvent*>(action) == nullptr &&
      dynamic_cast<const VelocityChangeEvent*>(action) == nullptr) {
    throw InputError(root.file(), path,
                     "a team scenario takes impulse, velocity_change and fault events only, "
                     "not '" +
                         event.type + "'");
  }
}

}  // namespace

void CheckEventVehicles(const std::vector<EventSpec>& events, int vehicles, bool onboard_sensors,
                        const YamlMap& root) {
  const bool team = vehicles > 1;
  const int flown = std::max(vehicles, 1);
  for (size_t i = 0; i < events.size(); ++i) {
    const std::string path = root.KeyPath("events") + "." + std::to_string(i);
    if (team) CheckTeamEventType(events[i], path, onboard_sensors, root);
    const EventTarget target = TargetOf(events[i].action.get());
    const bool fault = dynamic_cast<const FaultEvent*>(events[i].action.get()) != nullptr;
    if (target.vehicle && target.on_payload) {
      throw InputError(root.file(), path + ".vehicle",
                       "names the quadrotor a `body: quadrotor` event acts on; this event acts on "
                       "the payload");
    }
    if (team && !target.vehicle && !target.on_payload) {
      throw InputError(root.file(), path + ".vehicle",
                       std::string(fault ? "a team's fault" : "a team's quadrotor event") +
                           " names its vehicle (0 to " + std::to_string(vehicles - 1) + ")");
    }
    const int vehicle = target.vehicle.value_or(0);
    if (vehicle >= flown) {
      throw InputError(root.file(), path + ".vehicle",
                       "vehicle " + std::to_string(vehicle) + " is not in the scenario (" +
                           std::to_string(flown) + " vehicle" + (flown > 1 ? "s" : "") +
                           ", counted from 0)");
    }
  }
}

}  // namespace hpa
