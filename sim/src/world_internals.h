#pragma once
// MuJoCo access to a World, for sim/'s own tests and benchmarks only (World keeps its mjModel
// and mjData private so that nothing outside sim/ depends on MuJoCo through it).

#include <mujoco/mujoco.h>

#include "hpa/sim/world.h"
#include "offscreen_renderer.h"

namespace hpa::sim {

/// The World's MuJoCo model and data.
struct WorldInternals {
  /// The compiled model.
  static const mjModel* Model(const World& world) { return world.model_; }
  /// The simulation data (stepping it directly bypasses motors, sensors and events).
  static mjData* Data(World& world) { return world.data_; }
  /// The renderer of the World's cameras.
  static OffscreenRenderer& Renderer(World& world) { return *world.renderer_->offscreen_; }
};

}  // namespace hpa::sim
