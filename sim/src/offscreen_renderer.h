#pragma once
// Headless MuJoCo rendering through OSMesa or EGL (docs/design.md section 9): one GL context per
// renderer, created lazily on the first frame so runs that never render pay nothing.

#include <mujoco/mujoco.h>

#include <array>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "hpa/sim/gl_backend.h"

namespace hpa::sim {

/// Renders fixed cameras of one mjModel into BGR images; shadows, reflections and skybox off.
/// Not thread-safe; each Render makes its own context current, so renderers may take turns on
/// one thread. One back end per process (gl_context.h).
class OffscreenRenderer {
 public:
  /// Keeps a pointer to `model`, which must outlive the renderer; creates no GL state yet.
  explicit OffscreenRenderer(const mjModel* model, GlBackend backend = GlBackend::kOsMesa);
  ~OffscreenRenderer();
  OffscreenRenderer(const OffscreenRenderer&) = delete;
  OffscreenRenderer& operator=(const OffscreenRenderer&) = delete;

  /// Renders camera `camera_id` of the current `data` (kinematics must be up to date) at
  /// width x height (at most the model's offwidth x offheight) as CV_8UC3 BGR, top row first.
  /// Throws std::runtime_error if the GL context cannot be made or the size is too large.
  /// show_tendons = false leaves the cable out (the onboard camera: see world.cc).
  cv::Mat Render(mjData* data, int camera_id, int width_px, int height_px,
                 bool show_tendons = true);

  /// As Render above, into `bgr` (reallocated only when its size or type differs): with a
  /// single-sample offscreen buffer the pixels are read straight into it, no copy. A non-empty
  /// `region` renders only that part of the frame (the rest of `bgr` is left as it was).
  void Render(mjData* data, int camera_id, int width_px, int height_px, bool show_tendons,
              cv::Mat* bgr, const cv::Rect& region = cv::Rect());

  /// Makes the GL state now (a kept one if reuse allows, else a new context and MuJoCo's GL
  /// resources), as the first Render would, and leaves its context current; nothing if it exists.
  /// Throws as Render does.
  void Prepare();

  /// Whether geoms of `group` (0..5) are drawn by the following Render calls (MuJoCo's
  /// defaults: groups 0-2 drawn, 3-5 not).
  void SetGeomGroupVisible(int group, bool visible);

  /// Draws, in the following Render calls, copies of geom `geom_id` (its shape, size, material
  /// and orientation) centred at each of `positions_W` (m, world frame): a second object of the
  /// same look (a camera fault's distractor); a copy whose `box_sizes_m` entry (full sizes x, y,
  /// z) has no zero is a level box of that size in the geom's material. Empty: none.
  void SetGeomCopies(int geom_id, std::vector<std::array<double, 3>> positions_W,
                     std::vector<std::array<double, 3>> box_sizes_m = {});

  /// Whether Render leaves out the geoms the frame cannot show (scene_culling.h): on by default;
  /// the frame is the same either way, only faster.
  void SetCullHiddenGeoms(bool cull);

  /// How many geoms the last Render left out.
  int last_culled_geoms() const { return last_culled_geoms_; }

  /// True once the GL context exists (after the first Render).
  bool initialized() const;

  /// What renders (back end, EGL platform, GL_RENDERER); "" before the first Render.
  std::string GlDescription();

  /// True once the first Render took the GL state another renderer kept (GlContext::SetReuse:
  /// its context with MuJoCo's GL resources made for a model that renders the same).
  bool took_kept_state() const { return took_kept_state_; }

 private:
  struct Gl;  // GL context, mjvScene, mjrContext (hidden: keeps GL out of this header)
  // The GL state a finished renderer kept while reuse is on (at most one; under KeptGlMutex()).
  static std::unique_ptr<Gl>& KeptGl();
  // Frees a renderer's GL state: MuJoCo's resources, then the context (recycled if reuse is on).
  static void Release(std::unique_ptr<Gl> gl);
  // Appends the copies of SetGeomCopies to a scene mjv_updateScene just made.
  void AddGeomCopies(mjvScene* scene) const;
  const mjModel* model_;
  GlBackend backend_;
  std::unique_ptr<Gl> gl_;
  cv::Mat flip_buffer_;  // multisampled path only: the bottom-up frame turned top-down
  bool took_kept_state_ = false;
  bool cull_hidden_geoms_ = true;
  int last_culled_geoms_ = 0;
  bool geom_group_visible_[6] = {true, true, true, false, false, false};
  int copied_geom_ = -1;                                   // the geom SetGeomCopies copies
  std::vector<std::array<double, 3>> copy_positions_W_;   // where its copies are (m, world)
  std::vector<std::array<double, 3>> copy_box_sizes_m_;   // their box sizes (none or a 0: geom's)
};

}  // namespace hpa::sim
