#pragma once
// Scripted disturbances of a scenario (docs/design.md section 5). Each event type is a struct with
// its own parsing, validation and application, in its own file under harness/runner/src/events/,
// deriving from EventAction; a new type is that file (its struct declared here or in its own
// header) and one registration line in event_registry.cc.

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace hpa {

class YamlMap;
struct Params;
namespace sim {
class World;
}

/// What an event does to the world (type-erased: a new type needs no central list of types).
struct EventAction {
  virtual ~EventAction() = default;
  /// Applies the event at its start time.
  virtual void Apply(sim::World* world) const = 0;
  /// Why the event is implausible for a world with these parameters (the world's, with its
  /// overrides), or empty; printed as a warning at run start (the params are not known when the
  /// scenario is parsed).
  virtual std::string Warning(const Params& world_params) const { return {}; }
};

/// The gripper takes the payload where it is.
struct GripperGrabEvent final : EventAction {
  static GripperGrabEvent Parse(const YamlMap& map);
  void Apply(sim::World* world) const override;
};

/// The gripper (and a held payload) moves along a minimum-jerk path.
struct GripperMoveEvent final : EventAction {
  Eigen::Vector3d to_W_m = Eigen::Vector3d::Zero();  // target  (3)
  double duration_s = 0.0;
  static GripperMoveEvent Parse(const YamlMap& map);
  void Apply(sim::World* world) const override;
};

/// The gripper lets the payload go.
struct GripperReleaseEvent final : EventAction {
  static GripperReleaseEvent Parse(const YamlMap& map);
  void Apply(sim::World* world) const override;
};

/// An impulse on the payload or the quadrotor, spread over a short time.
struct ImpulseEvent final : EventAction {
  Eigen::Vector3d impulse_W_Ns = Eigen::Vector3d::Zero();  // (3)
  double duration_s = 0.01;
  bool on_payload = true;  // body: payload or quadrotor
  std::optional<int> vehicle;  // the quadrotor it pushes (`vehicle`; a team's must name it)
  static ImpulseEvent Parse(const YamlMap& map);
  void Apply(sim::World* world) const override;
  std::string Warning(const Params& world_params) const override;
};

/// A velocity change of the payload or the quadrotor, at once.
struct VelocityChangeEvent final : EventAction {
  Eigen::Vector3d dv_W_mps = Eigen::Vector3d::Zero();  // added to the body's velocity  (3)
  bool on_payload = true;                              // body: payload or quadrotor
  std::optional<int> vehicle;  // the quadrotor it acts on (`vehicle`; a team's must name it)
  static VelocityChangeEvent Parse(const YamlMap& map);
  void Apply(sim::World* world) const override;
};

/// A constant force on the quadrotor for a while.
struct WindEvent final : EventAction {
  Eigen::Vector3d force_W_N = Eigen::Vector3d::Zero();  // constant force on the quadrotor  (3)
  // or: a wind velocity added to the profile's wind, acting through the drag of the quadrotor,
  // its rotors and the payload (flight profile; the ideal world has no air)  (3)
  std::optional<Eigen::Vector3d> velocity_W_mps;
  double duration_s = 0.0;
  static WindEvent Parse(const YamlMap& map);
  void Apply(sim::World* world) const override;
};

/// One scripted disturbance: when, what, and the name it was written with.
struct EventSpec {
  double at_s = 0.0;  // simulated time it starts
  std::string type;   // registered name, as written in YAML
  std::shared_ptr<const EventAction> action;
};

/// One registered event type.
struct EventRegistration {
  std::string name;         // as written in YAML (`type:`)
  std::string description;  // one line for --help
  // reads and validates the type's keys
  std::function<std::shared_ptr<const EventAction>(const YamlMap&)> parse;
};

/// Every event type, in registration order.
const std::vector<EventRegistration>& EventTypes();

/// Adds an event type at run time (tests, plugins); throws std::invalid_argument on an empty or
/// duplicate name. Its `parse` reads the type's own keys from the event map.
void RegisterEventType(EventRegistration registration);

/// Parses one event map (`at`, `type` and the type's own keys); throws InputError naming the
/// key, listing the registered types for an unknown one.
EventSpec ParseEvent(const YamlMap& map);

/// Applies an event to the world.
void ApplyEvent(const EventSpec& event, sim::World* world);

}  // namespace hpa
