#pragma once
// Image formation of the payload camera after the renderer: the renderer draws an ideal pinhole
// image with one sample per pixel; this model turns it into what the camera's sensor reads out:
// motion blur over the exposure, lens distortion (radial-tangential, the calibration in
// models/params.yaml), the lens point-spread function, and shot and read noise with a gain,
// quantised to 8 bits. Parameters: WorldProfile::camera (models/profiles/*.yaml).

#include <Eigen/Core>
#include <cstdint>
#include <future>
#include <opencv2/core.hpp>
#include <vector>

#include "hpa/models/params.h"
#include "hpa/sim/world_profile.h"

namespace hpa::sim {

/// values[i] += sd[values[i]] * unit_normal[i] for n 8-bit values, the sum in float rounded to
/// nearest (even) and clamped to 0..255 (cv::saturate_cast); `sd` has 256 entries, one per level.
void AddLevelScaledNoise(uint8_t* values, const float* sd, const float* unit_normal, size_t n);

/// How a float remap map's values are ordered: never decreasing along each row (an x map), down
/// each column (a y map), or neither.
enum class MapOrder { kNone, kIncreasingAlongRows, kIncreasingDownColumns };

/// `order` if every value of the CV_32FC1 `map` keeps it, else kNone.
MapOrder CheckedMapOrder(const cv::Mat& map, MapOrder order);

/// The least and greatest value of the CV_32FC1 `map` over `area` (non-empty, inside the map).
/// An ordered map's extremes lie on the area's first and last column (or row), and only those
/// are read: the same values as cv::minMaxLoc over the whole area.
void MapRange(const cv::Mat& map, const cv::Rect& area, MapOrder order, double* min, double* max);

/// Turns pinhole renders into sensor images. Deterministic: the noise of frame k depends only on
/// (seed, k); the model owns its buffers and reuses them from frame to frame.
class CameraImageModel {
 public:
  /// Camera intrinsics and distortion from `params`; the profile's optics and sensor; `seed`
  /// keys the noise.
  CameraImageModel(const Params& params, const CameraImageProfile& profile, uint64_t seed);
  /// Computes the process-wide tables a model of `params` reads (the noise samples, the
  /// distortion maps), which every model in the process shares: a process that forks workers
  /// calls it first so that they inherit the tables instead of each computing its own.
  static void PrepareSharedTables(const Params& params);
  /// Computes the shared tables a model of `params` and `profile` reads (the noise samples if the
  /// profile adds noise, the maps if the lens distorts), so that a caller may compute them on
  /// another thread before the model is made; the model then finds them ready.
  static void PrepareTablesFor(const Params& params, const CameraImageProfile& profile);
  /// The N(0, 1) samples the noise reads, shared by every model in the process: exactly what
  /// std::normal_distribution<float>(0, 1) draws from std::mt19937_64(0x5eed), computed once.
  static const std::vector<float>& UnitNormalTable();

  /// Focal length (px) of the pinhole render the model expects: the sensor's own focal length
  /// without distortion; with barrel distortion, short enough that the render covers every
  /// sensor pixel's undistorted ray.
  double render_focal_px() const { return render_focal_px_; }
  /// Vertical field of view (deg) of that render at the sensor's size (MuJoCo camera fovy).
  double render_fovy_deg() const;

  /// Sensor image (CV_8UC3 BGR, the sensor's size) of `pinhole` (a render of the sensor's size
  /// at render_focal_px). `blur_px` is the image motion (render pixels) over the exposure of the
  /// region `blur_region` (render pixels; empty: the whole frame): the fast motion-blur
  /// approximation smears that region along it, fading out over a band around it (no seam).
  /// `frame_index` keys the noise. A non-empty `sensor_region` computes only that part of the
  /// sensor image (equal to the whole frame's there), reading only
  /// RenderRegion(sensor_region, blur_px) of `pinhole`.
  void Apply(const cv::Mat& pinhole, const Eigen::Vector2d& blur_px, const cv::Rect& blur_region,
             uint64_t frame_index, cv::Mat* sensor, const cv::Rect& sensor_region = cv::Rect());

  /// As Apply without motion blur (used after an exact sub-frame average).
  void ApplyOptics(const cv::Mat& pinhole, uint64_t frame_index, cv::Mat* sensor,
                   const cv::Rect& sensor_region = cv::Rect());

  /// The part of the pinhole render that the sensor region (empty: the whole sensor) reads,
  /// through the PSF, the lens and a motion blur of blur_px.
  cv::Rect RenderRegion(const cv::Rect& sensor_region, const Eigen::Vector2d& blur_px) const;

  const CameraImageProfile& profile() const { return profile_; }
  /// Render pixel x and y (CV_32FC1, sensor size) each sensor pixel reads; empty without
  /// distortion.
  const cv::Mat& map_x() const { return map_x_; }
  const cv::Mat& map_y() const { return map_y_; }
  /// The orders of map_x() and map_y() (kNone unless checked for every value).
  MapOrder map_x_order() const { return map_x_order_; }
  MapOrder map_y_order() const { return map_y_order_; }

 private:
  void Remap(const cv::Mat& pinhole, const cv::Rect& area, cv::Mat* out);
  void AddNoise(uint64_t frame_index, const cv::Rect& area, cv::Mat* image) const;
  int PsfRadiusPx() const;
  int MotionBlurRadiusPx(const Eigen::Vector2d& blur_px) const;

  Params params_;
  CameraImageProfile profile_;
  uint64_t seed_;
  double render_focal_px_;
  bool distorted_;
  cv::Mat map_x_, map_y_;  // the same in float (render regions)
  MapOrder map_x_order_ = MapOrder::kNone, map_y_order_ = MapOrder::kNone;  // checked orders
  cv::Mat map1_, map2_;             // sensor pixel -> render pixel (fixed-point maps for remap)
  cv::Mat blurred_, remapped_;      // reused frame buffers
  std::vector<float> noise_sd_dn_;  // noise std (DN) per 8-bit level: shot + read, times gain
  std::shared_future<void> noise_table_;  // UnitNormalTable's computation, while it runs
};

}  // namespace hpa::sim
