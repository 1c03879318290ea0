#pragma once
// Contacts of the payload and a vehicle (a component of sim::World): contact episodes per pair
// and the closest the payload has come to the vehicle; a payload striking a rotor is reported to
// the world, which latches the crash. The world binds it to the geometry it watches
// (ContactsBinding); it reaches nothing else of that world.

#include <array>

// MuJoCo's model and data, only pointed to here (sim/src includes MuJoCo)
struct mjModel_;
struct mjData_;

namespace hpa::sim {

/// What Contacts reads of its world, filled by that world: MuJoCo's model and data and the ids
/// of the bodies and geoms it watches.
struct ContactsBinding {
  const mjModel_* model = nullptr;                 // the world's MuJoCo model
  const mjData_* data = nullptr;                   // the world's MuJoCo data
  int payload_body = -1, payload_geom = -1;        // the payload and its sphere
  int quad_body = -1, quad_box_geom = -1;          // the vehicle and its body box
  std::array<int, 4> rotor_disc_geom{{-1, -1, -1, -1}};  // its rotor disks  (4)
  int ground_geom = -1;
  int gripper_geom = -1;  // the gripper's rod (-1: the scene has none)
};

/// Contact episodes since Reset (a pair counts once each time it starts touching).
struct ContactCounts {
  int payload_body = 0;     // payload against the quadrotor's body box
  int payload_rotor = 0;    // payload against a rotor disk (a crash: rotor_strike)
  int payload_ground = 0;   // payload against the ground
  int quad_ground = 0;      // quadrotor against the ground (a crash)
  int payload_gripper = 0;  // payload against the gripper rod while not held (flight contact)
};

/// The payload's contacts with the vehicle, the ground and the gripper.
class Contacts {
 public:
  /// Bound to the world's geometry; model and data must be set.
  explicit Contacts(const ContactsBinding& binding);

  /// Contact episodes since Reset.
  const ContactCounts& counts() const { return counts_; }
  /// Smallest surface-to-surface distance (m) between the payload sphere and the vehicle (body
  /// box and rotor disks) since Reset; negative: they overlapped by that much.
  double payload_quad_min_distance_m() const { return payload_quad_min_distance_m_; }
  /// Surface-to-surface distance (m) between the payload and the vehicle now.
  double PayloadQuadDistance() const;

  // What the owning world calls, in its step order.
  /// No episodes, nothing touching, the distance of the current state (the world's Reset).
  void Reset();
  /// This step's contacts: new episodes and the closest distance; true when the payload struck a
  /// rotor (the world latches its crash).
  bool Update();

 private:
  ContactsBinding b_;  // the world whose contacts these are
  ContactCounts counts_;
  double payload_quad_min_distance_m_ = 0.0;
  bool touching_[5] = {false, false, false, false, false};  // ContactCounts fields, last step
};

}  // namespace hpa::sim
