#pragma once
// The world's rendered cameras (a component of sim::World): the payload camera (a pinhole render
// turned into the sensor's image by the profile's camera image model) and the chase camera for
// videos, through OSMesa or EGL; and the appearance drawn from the seed. Reached through
// World::renderer().

#include <Eigen/Core>
#include <future>
#include <memory>
#include <opencv2/core.hpp>

// MuJoCo's data, only pointed to here (sim/src includes MuJoCo)
struct mjData_;

namespace hpa::sim {

class World;
struct WorldConfig;
class OffscreenRenderer;
class CameraImageModel;

/// Wall time of one payload-camera frame, by stage.
struct CameraFrameTiming {
  double render_ms = 0.0;       // scene update, rasterisation, pixel read-out (all sub-frames)
  double image_model_ms = 0.0;  // motion blur, distortion, PSF, noise
};

/// The payload and chase cameras of a world.
class Renderer {
 public:
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Renders one payload-camera frame of a world of `config` and keeps its GL context, with the
  /// shaders llvmpipe compiled for it, for the process's next renderer of the same size: a
  /// process that forks workers calls it first so that each worker's first frame skips context
  /// creation and shader compilation. OSMesa only, and only where llvmpipe rasterises on the
  /// calling thread (LP_NUM_THREADS unset, which this sets to 0, or 0; and no context made in
  /// the process before): its worker threads do not survive fork. Returns whether the context
  /// was kept; same pixels either way.
  static bool PrewarmForFork(const WorldConfig& config);

  /// Payload camera frame, CV_8UC3 BGR, 1280x720, top row first (first call creates the GL
  /// context of config.gl_backend): a single-sample pinhole render turned into the sensor's
  /// image by the profile's camera image model (CameraImageModel: motion blur, distortion, PSF,
  /// noise).
  cv::Mat RenderPayloadCamera();
  /// As above, into `bgr` (reallocated only when its size or type differs). A non-empty
  /// `region` computes only that part of the image, equal to the whole frame's there (the rest
  /// of `bgr` is left as it was): what a detector reading only a region needs.
  void RenderPayloadCamera(cv::Mat* bgr, const cv::Rect& region = cv::Rect());
  /// The payload camera's image size (pixels).
  cv::Size PayloadCameraSize() const;
  /// Wall time of the last payload frame's render and of its image model.
  const CameraFrameTiming& last_camera_timing() const { return camera_timing_; }
  /// Image motion (render pixels) of the payload's centre over one exposure now, and the
  /// region of the render the payload covers (for the fast motion-blur approximation).
  Eigen::Vector2d PayloadImageMotionPx(cv::Rect* region) const;
  /// Chase camera frame for videos, CV_8UC3 BGR, top row first (at most 1280x720).
  cv::Mat RenderChaseCamera(int width_px, int height_px);

 private:
  friend class World;
  friend struct WorldInternals;
  // the world's appearance drawn (if asked), its GL renderer made and the camera's tables started
  explicit Renderer(World& world);
  // floor shade, texture scale and lights drawn from the seed
  void RandomizeAppearance();

  World& w_;  // the world this renders
  std::unique_ptr<OffscreenRenderer> offscreen_;
  std::unique_ptr<CameraImageModel> camera_image_;  // created with the first payload frame
  std::future<void> camera_tables_;            // its shared tables, computed from construction on
  mjData_* subframe_data_ = nullptr;           // kinematics of exposure sub-frames
  cv::Mat pinhole_, subframe_, subframe_sum_;  // reused frame buffers
  CameraFrameTiming camera_timing_;
};

}  // namespace hpa::sim
