#pragma once
// Headless MuJoCo rendering through OSMesa (DESIGN.md section 8): one GL context per process,
// created lazily on the first frame so runs that never render pay nothing.

#include <mujoco/mujoco.h>

#include <memory>
#include <opencv2/core.hpp>

namespace hpa::sim {

/// Renders fixed cameras of one mjModel into BGR images; shadows, reflections and skybox off.
/// Not thread-safe; OSMesa allows one current context per thread, so use one per process.
class OffscreenRenderer {
 public:
  /// Keeps a pointer to `model`, which must outlive the renderer; creates no GL state yet.
  explicit OffscreenRenderer(const mjModel* model);
  ~OffscreenRenderer();
  OffscreenRenderer(const OffscreenRenderer&) = delete;
  OffscreenRenderer& operator=(const OffscreenRenderer&) = delete;

  /// Renders camera `camera_id` of the current `data` (kinematics must be up to date) at
  /// width x height (at most the model's offwidth x offheight) as CV_8UC3 BGR, top row first.
  /// Throws std::runtime_error if the GL context cannot be made or the size is too large.
  /// show_tendons = false leaves the cable out (the onboard camera: see world.cc).
  cv::Mat Render(mjData* data, int camera_id, int width_px, int height_px,
                 bool show_tendons = true);

  /// True once the OSMesa context exists (after the first Render).
  bool initialized() const;

 private:
  struct Gl;  // OSMesa context, mjvScene, mjrContext (hidden: keeps GL out of this header)
  const mjModel* model_;
  std::unique_ptr<Gl> gl_;
};

}  // namespace hpa::sim
