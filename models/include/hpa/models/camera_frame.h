#pragma once
// The payload camera's rendered frame: the one type the simulator renders into (sim/,
// payload_camera.h) and the flight stack detects in (flight/, in process or through the
// lockstep protocol's frame ring). Uses OpenCV's core types: sim/ and the flight code link
// OpenCV; models' own sources do not include this header.

#include <functional>
#include <opencv2/core.hpp>

namespace hpa {

/// One rendered payload-camera frame, read out as the region of interest the flight stack asked
/// for and, for when that region cannot decide, whole.
struct CameraFrame {
  double capture_time_s = 0.0;  // when the camera captured it (its delivery counts from here)
  cv::Rect region;              // the region of interest read out (empty: none, only whole)
  cv::Mat region_bgr;  // CV_8UC3 of the camera's size, top row first; valid inside `region` only
  cv::Mat whole_bgr;   // CV_8UC3, top row first, the whole frame (empty: not read out)
  int region_slot = -1, whole_slot = -1;  // their frame-ring slots (-1: not in the ring)
};

/// Reads out the whole image of a frame that holds only its region, from the same exposure (the
/// in-process camera renders it only when the region cannot decide); returns that image.
using WholeFrameReader = std::function<const cv::Mat&()>;

}  // namespace hpa
