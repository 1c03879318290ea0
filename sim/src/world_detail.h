#pragma once
// Private pieces the World's source files share: the MuJoCo warning collector.

#include <cstdint>
#include <string>

namespace hpa::sim {

/// Routes MuJoCo's warnings into a per-thread buffer (once per process).
void InstallWarningHandler();

/// The warnings collected on this thread since the last call ("" if none).
std::string TakeWarnings();

/// MJCF geom group of the gripper's visual (drawn in the chase camera while it holds the payload).
constexpr int kGripperGeomGroup = 3;

}  // namespace hpa::sim
