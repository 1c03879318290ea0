#pragma once
// Contacts of the payload and the vehicle (a component of sim::World): contact episodes per pair
// and the closest the payload has come to the vehicle; a payload striking a rotor latches the
// world's crash.

namespace hpa::sim {

class World;

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
  /// Contact episodes since Reset.
  const ContactCounts& counts() const { return counts_; }
  /// Smallest surface-to-surface distance (m) between the payload sphere and the vehicle (body
  /// box and rotor disks) since Reset; negative: they overlapped by that much.
  double payload_quad_min_distance_m() const { return payload_quad_min_distance_m_; }
  /// Surface-to-surface distance (m) between the payload and the vehicle now.
  double PayloadQuadDistance() const;

 private:
  friend class World;
  explicit Contacts(World& world) : w_(world) {}
  // no episodes, nothing touching, the distance of the current state (World::Reset)
  void Reset();
  // this step's contacts: new episodes, the closest distance, a rotor strike
  void Update();

  World& w_;  // the world whose contacts these are
  ContactCounts counts_;
  double payload_quad_min_distance_m_ = 0.0;
  bool touching_[5] = {false, false, false, false, false};  // ContactCounts fields, last step
};

}  // namespace hpa::sim
