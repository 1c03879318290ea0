#pragma once
// Payload detector: finds the red spherical payload in a payload-camera frame and recovers its
// centre in the camera frame C from the fitted ellipse (exact perspective geometry of a sphere).

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <optional>
#include <utility>
#include <vector>

#include "hpa/estimator/payload_masks.h"
#include "hpa/models/camera_model.h"
#include "hpa/models/params.h"
#include "hpa/models/sensor_types.h"

namespace hpa {

/// Thresholds of the detector; the defaults were tuned on synthetic and rendered 1280x720 frames.
struct PayloadDetectorConfig {
  PayloadMaskThresholds masks;        // red hue band, saturation and value; the occluders' value
  double min_area_px2 = 200.0;        // smaller: "too small" (radius 8 px = payload 2.3 m away)
  double min_iou = 0.90;              // blob vs fitted ellipse (clipped to the image)
  double min_visible_outline = 0.60;  // share of the fitted outline inside the image
  int occluder_grow_px = 3;           // outline points this close to an occluder are not fitted
  double min_fit_share = 0.25;        // share of the blob's outline left to fit, at least
  int min_fit_points = 16;            // outline points left to fit, at least
  double min_semi_minor_px = 2.0;     // smaller fitted ellipse: a poor fit
  int outline_samples = 72;           // samples of the fitted outline for min_visible_outline
  double min_radial_offset_px = 2.0;  // closer to the principal point: major axis from the fit
  double edge_bias_px = 0.5;          // contour runs through edge pixel centres: add to axes
};

/// The detections of the last two frames: what the next frame's region of interest follows.
struct RecentDetections {
  PayloadDetection previous;  // the frame's before the last (found = false until two frames)
  PayloadDetection last;      // the last frame's
  /// The next frame's detection: the last one becomes the previous.
  void Push(PayloadDetection next) {
    previous = std::move(last);
    last = std::move(next);
  }
};

/// Red-sphere detector on 1280x720 BGR frames of a camera with the lens distortion of
/// Params::camera_distortion; deterministic. The centre and radius it reports are in the ideal
/// (undistorted, pinhole) image.
class PayloadDetector {
 public:
  /// Uses the camera intrinsics (focal from fovy, principal point at the image centre) and the
  /// payload radius of `params`.
  explicit PayloadDetector(const Params& params, const PayloadDetectorConfig& config = {});

  /// Detects the payload in one BGR frame captured at time_s. found=false with a reason ("no
  /// payload in view", "too small", "partly out of view", "poor ellipse fit") instead of a guess.
  /// Not thread-safe: reuses its buffers from call to call.
  PayloadDetection Detect(const cv::Mat& bgr, double time_s) const;

  /// Detects the payload reading only `region` of the frame (the rest may be stale): the same
  /// result as Detect on the whole frame whenever it returns one (the payload being the largest
  /// red object in view), nullopt when the region cannot decide (nothing found in it, or the
  /// payload at its edge): then detect on the whole frame.
  std::optional<PayloadDetection> DetectInRegion(const cv::Mat& bgr, const cv::Rect& region,
                                                 double time_s) const;

  /// Region of the real image for the frame after `recent.last`: around its centre through the
  /// lens, half a side of 1.5 ball radii plus margin_px (how far the ball may move between
  /// frames); when the frame before found the ball too, around the centre moved on by the last
  /// motion, with half the margin plus half that motion. Empty when the last frame found nothing.
  cv::Rect RegionAround(const RecentDetections& recent, double margin_px) const;

  const PayloadDetectorConfig& config() const { return config_; }

 private:
  // Detect reading only `area` of the frame; *inside_area tells whether the result depends on
  // nothing outside it (always true for the whole frame when found)
  PayloadDetection DetectInArea(const cv::Mat& bgr, const cv::Rect& area, double time_s,
                                bool* inside_area) const;

  Params params_;
  PayloadDetectorConfig config_;
  mutable std::vector<cv::Point2f> undistorted_;  // outline in the ideal image, reused
  struct Buffers {                                // frame-sized working images, reused
    cv::Mat mask, occluder, occluded_near;        // red mask, dark pixels, grown near the blob
  };
  mutable Buffers buffers_;
};

}  // namespace hpa
