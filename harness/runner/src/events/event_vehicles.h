#pragma once
// Which vehicle each event of a scenario acts on, checked against the scenario's vehicles: a
// team's quadrotor events and faults name theirs, a payload's names none, and no event names a
// vehicle the scenario does not fly (a single-vehicle scenario flies vehicle 0).

#include <vector>

#include "hpa/scenarios/events.h"

namespace hpa {

class YamlMap;

/// Checks the events of a scenario of `vehicles` vehicles (0: the single vehicle) against its
/// kind: a team takes impulse, velocity_change and fault events only, the faults of a motor,
/// and of an IMU, VIO or rate gyro when its vehicles carry them (`onboard_sensors`), each
/// quadrotor event and fault naming a vehicle from 0 to vehicles - 1. `root` is the scenario's
/// map (file and key paths of the messages); throws InputError naming `events.I.KEY`.
void CheckEventVehicles(const std::vector<EventSpec>& events, int vehicles, bool onboard_sensors,
                        const YamlMap& root);

}  // namespace hpa
