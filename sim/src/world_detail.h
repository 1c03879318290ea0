#pragma once
// Private pieces the World's source files share: the MuJoCo warning collector and the seeds of
// the world's own random generators.

#include <cstdint>
#include <string>

namespace hpa::sim {

/// Routes MuJoCo's warnings into a per-thread buffer (once per process).
void InstallWarningHandler();

/// The warnings collected on this thread since the last call ("" if none).
std::string TakeWarnings();

/// MJCF geom group of the gripper's visual (drawn in the chase camera while it holds the payload).
constexpr int kGripperGeomGroup = 3;

/// Seed of one of the world's own generators (mismatch, gusts, VIO drift, rate gyro,
/// appearance), apart from the sensor noise stream: seed * golden-ratio constant + salt.
inline uint64_t DerivedSeed(uint64_t seed, uint64_t salt) {
  return seed * 0x9E3779B97F4A7C15ULL + salt;
}

}  // namespace hpa::sim
