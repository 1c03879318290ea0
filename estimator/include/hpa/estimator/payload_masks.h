#pragma once
// The payload detector's two pixel masks, computed from BGR in one pass: the red mask (the
// detector's hue bands, saturation and value thresholds on OpenCV's 8-bit HSV) and the
// occluder mask (very dark pixels). The same masks as cv::cvtColor(COLOR_BGR2HSV) followed by
// cv::inRange, without the HSV image: a pixel's hue is computed only when its saturation and
// value pass (the grey floor, most of a frame, fails the saturation test).

#include <opencv2/core.hpp>

namespace hpa {

/// Thresholds of the two masks (OpenCV's 8-bit HSV: hue 0..180, saturation and value 0..255);
/// the defaults are the detector's, tuned on synthetic and rendered 1280x720 frames.
struct PayloadMaskThresholds {
  int hue_max_low = 10;         // red hue band [0, hue_max_low] U [hue_min_high, 180]
  int hue_min_high = 170;       // (OpenCV hue is 0..180)
  int saturation_min = 110;     // the grey floor has saturation ~0, the payload ~255
  int value_min = 40;           // the shaded side of the sphere stays above this
  int occluder_value_max = 50;  // darker pixels occlude (the cable; floor is >= 75)
};

/// Writes the red mask and the occluder mask (CV_8UC1, 255 where set, 0 elsewhere; the size of
/// `bgr`, a CV_8UC3 image or sub-image) of `bgr`, reusing the masks' buffers.
void PayloadMasks(const cv::Mat& bgr, const PayloadMaskThresholds& thresholds, cv::Mat* red,
                  cv::Mat* occluder);

}  // namespace hpa
