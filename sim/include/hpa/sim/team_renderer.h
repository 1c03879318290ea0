#pragma once
// The cameras of a team's video (docs/cooperative.md): a chase camera that keeps every vehicle and
// the payload in view, and each vehicle's onboard payload camera. They draw a render-only copy of
// the team's scene (cameras, rotor discs, a checker floor, lights added) posed from the team
// world's state, so rendering never touches the physics model or its data.

#include <memory>
#include <opencv2/core.hpp>
#include <vector>

namespace hpa::sim {

class TeamWorld;

/// Renders a TeamWorld's chase and onboard cameras off-screen (OSMesa or EGL, the world's
/// TeamWorldConfig::gl_backend) into BGR images. Not thread-safe; the GL context is made on the
/// first frame. Get it through TeamWorld::renderer().
class TeamRenderer {
 public:
  static constexpr int kOnboardWidthPx = 320;   // onboard camera's default image width
  static constexpr int kOnboardHeightPx = 180;  // onboard camera's default image height
  static constexpr int kMaxWidthPx = 1280;      // widest image either camera renders
  static constexpr int kMaxHeightPx = 720;      // tallest image either camera renders

  /// Compiles the render-only scene of `world` (which must outlive the renderer); no GL yet.
  /// Throws std::runtime_error if MuJoCo cannot compile it.
  explicit TeamRenderer(const TeamWorld& world);
  ~TeamRenderer();
  TeamRenderer(const TeamRenderer&) = delete;
  TeamRenderer& operator=(const TeamRenderer&) = delete;

  /// The chase camera now into `bgr` (CV_8UC3, width_px x height_px, at most kMaxWidthPx x
  /// kMaxHeightPx): from behind (-y, turned 25 deg about z) and above the team's centre (the
  /// mean of the payload's and the vehicles' positions), at a fixed distance that fits the
  /// hanging team with room for its motion; cables drawn, a slack one in orange. Throws
  /// std::invalid_argument for a size out of range, std::runtime_error if no GL context can be
  /// made.
  void RenderChaseCamera(int width_px, int height_px, cv::Mat* bgr);
  /// As above, returned.
  cv::Mat RenderChaseCamera(int width_px, int height_px);

  /// Vehicle's onboard camera now into `bgr`: a pinhole image (no lens or sensor model) from the
  /// vehicle's Params payload camera (t_BC_B_m, R_BC, camera_fovy_deg) at width_px x height_px.
  /// Throws std::out_of_range for a vehicle outside 0 .. N-1, else as RenderChaseCamera.
  void RenderOnboardCamera(int vehicle, int width_px, int height_px, cv::Mat* bgr);
  /// As above at kOnboardWidthPx x kOnboardHeightPx, returned.
  cv::Mat RenderOnboardCamera(int vehicle);
  /// Vehicle's payload camera now into `bgr` as the camera image model expects its pinhole
  /// render (CameraImageModel: the sensor's size, its render_fovy_deg()): the vehicle's Params
  /// mount at width_px x height_px and vertical field of view fovy_deg, the cables drawn iff
  /// show_cables (CameraImageProfile::draw_cable), the payload's struts in the vehicles' dark
  /// grey (the detector looks for one red ball; a red strut would join its blob). The video's
  /// cameras are left as they were. Throws std::invalid_argument for fovy_deg outside (0, 180),
  /// else as the RenderOnboardCamera above.
  void RenderOnboardCamera(int vehicle, int width_px, int height_px, double fovy_deg,
                           bool show_cables, cv::Mat* bgr);

  /// Vehicle's colour in the pictures (its rotor discs; BGR, 0..255), for an inset's frame.
  cv::Scalar VehicleColorBgr(int vehicle) const;

  /// Wall time of the last Render call (ms): posing the scene, rendering and reading pixels.
  double last_render_ms() const { return last_render_ms_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  double last_render_ms_ = 0.0;
};

}  // namespace hpa::sim
