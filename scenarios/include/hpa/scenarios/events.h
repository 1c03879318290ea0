#pragma once
// Scripted disturbances of a scenario (DESIGN.md section 5). Each event type is a struct with its
// own parsing, validation and application, in its own file under scenarios/src/events/; a new
// type is that file, its entry in EventAction and one registration line in event_registry.cc.

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace hpa {

class YamlMap;
namespace sim {
class World;
}

/// The gripper takes the payload where it is.
struct GripperGrabEvent {
  static GripperGrabEvent Parse(const YamlMap& map);
  void Apply(sim::World* world) const;
};

/// The gripper (and a held payload) moves along a minimum-jerk path.
struct GripperMoveEvent {
  Eigen::Vector3d to_W_m = Eigen::Vector3d::Zero();  // target  (3)
  double duration_s = 0.0;
  static GripperMoveEvent Parse(const YamlMap& map);
  void Apply(sim::World* world) const;
};

/// The gripper lets the payload go.
struct GripperReleaseEvent {
  static GripperReleaseEvent Parse(const YamlMap& map);
  void Apply(sim::World* world) const;
};

/// An impulse on the payload or the quadrotor, spread over a short time.
struct ImpulseEvent {
  Eigen::Vector3d impulse_W_Ns = Eigen::Vector3d::Zero();  // (3)
  double duration_s = 0.01;
  bool on_payload = true;  // body: payload or quadrotor
  static ImpulseEvent Parse(const YamlMap& map);
  void Apply(sim::World* world) const;
};

/// A constant force on the quadrotor for a while.
struct WindEvent {
  Eigen::Vector3d force_W_N = Eigen::Vector3d::Zero();  // constant force on the quadrotor  (3)
  // or: a wind velocity added to the profile's wind, acting through the drag of the quadrotor,
  // its rotors and the payload (flight profile; the ideal world has no air)  (3)
  std::optional<Eigen::Vector3d> velocity_W_mps;
  double duration_s = 0.0;
  static WindEvent Parse(const YamlMap& map);
  void Apply(sim::World* world) const;
};

/// What an event does.
using EventAction =
    std::variant<GripperGrabEvent, GripperMoveEvent, GripperReleaseEvent, ImpulseEvent, WindEvent>;

/// One scripted disturbance: when, what, and the name it was written with.
struct EventSpec {
  double at_s = 0.0;  // simulated time it starts
  std::string type;   // registered name, as written in YAML
  EventAction action;
};

/// One registered event type.
struct EventRegistration {
  std::string name;                                  // as written in YAML (`type:`)
  std::string description;                           // one line for --help
  std::function<EventAction(const YamlMap&)> parse;  // reads and validates the type's keys
};

/// Every event type, in registration order.
const std::vector<EventRegistration>& EventTypes();

/// Parses one event map (`at`, `type` and the type's own keys); throws InputError naming the
/// key, listing the registered types for an unknown one.
EventSpec ParseEvent(const YamlMap& map);

/// Applies an event to the world.
void ApplyEvent(const EventSpec& event, sim::World* world);

}  // namespace hpa
