// The detector's one-pass masks are OpenCV's HSV conversion and inRange, pixel for pixel, on
// every 8-bit BGR colour, for the detector's thresholds, for bands that reach every branch of the
// hue formula and for thresholds beyond the 8-bit range.
#include "hpa/estimator/payload_masks.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <vector>

#include "hpa/estimator/payload_detector.h"

namespace hpa {
namespace {

// Every BGR colour at least once, in rows of width_px (the last row padded with black).
cv::Mat EveryColour(int width_px) {
  const int rows = ((1 << 24) + width_px - 1) / width_px;
  cv::Mat bgr(rows, width_px, CV_8UC3, cv::Scalar::all(0));
  for (int i = 0; i < (1 << 24); ++i) {
    bgr.at<cv::Vec3b>(i / width_px, i % width_px) =
        cv::Vec3b(static_cast<uchar>(i & 255), static_cast<uchar>((i >> 8) & 255),
                  static_cast<uchar>(i >> 16));
  }
  return bgr;
}

// The masks as cv::cvtColor and cv::inRange give them.
void OpenCvMasks(const cv::Mat& bgr, const PayloadMaskThresholds& t, cv::Mat* red,
                 cv::Mat* occluder) {
  cv::Mat hsv, low, high;
  cv::cvtColor(bgr, hsv, cv::COLOR_BGR2HSV);
  cv::inRange(hsv, cv::Scalar(0, t.saturation_min, t.value_min),
              cv::Scalar(t.hue_max_low, 255, 255), low);
  cv::inRange(hsv, cv::Scalar(t.hue_min_high, t.saturation_min, t.value_min),
              cv::Scalar(180, 255, 255), high);
  cv::bitwise_or(low, high, *red);
  cv::inRange(hsv, cv::Scalar(0, 0, 0), cv::Scalar(180, 255, t.occluder_value_max), *occluder);
}

// Rows of 4096 pixels go through the sixteen-at-a-time pass, rows of 15 through the scalar one.
TEST(PayloadMasksTest, EqualOpenCvsHsvMasksOnEveryColour) {
  const PayloadMaskThresholds shipped = PayloadDetectorConfig().masks;
  // fields in order: hue_max_low, hue_min_high, saturation_min, value_min, occluder_value_max
  // wide bands: hues from the green and blue branches, every saturation and value
  const PayloadMaskThresholds wide{75, 120, 0, 0, 254};
  // the narrowest: only full saturation and value, hue 0 or 180, no occluder
  const PayloadMaskThresholds narrow_high{0, 180, 255, 255, 0};
  // thresholds outside 0..255: every value passes, every pixel is an occluder
  const PayloadMaskThresholds beyond{10, 170, -3, -10, 300};
  for (const int width_px : {4096, 15}) {
    const cv::Mat bgr = EveryColour(width_px);
    for (const PayloadMaskThresholds& t : {shipped, wide, narrow_high, beyond}) {
      cv::Mat red, occluder, want_red, want_occluder;
      PayloadMasks(bgr, t, &red, &occluder);
      OpenCvMasks(bgr, t, &want_red, &want_occluder);
      EXPECT_EQ(cv::countNonZero(red != want_red), 0)
          << "red, rows of " << width_px << ", hue_max_low " << t.hue_max_low;
      EXPECT_EQ(cv::countNonZero(occluder != want_occluder), 0)
          << "occluder, rows of " << width_px << ", value max " << t.occluder_value_max;
      EXPECT_GT(cv::countNonZero(want_red), 0) << "the band selects some colours";
    }
  }
}

// On a sub-image the masks cover the sub-image only, at its own size.
TEST(PayloadMasksTest, SubImageGivesMasksOfItsSize) {
  cv::Mat bgr(40, 60, CV_8UC3, cv::Scalar(30, 30, 200));      // red
  bgr(cv::Rect(0, 0, 60, 20)).setTo(cv::Scalar(10, 10, 10));  // dark top half
  cv::Mat red, occluder;
  PayloadMasks(bgr(cv::Rect(10, 10, 30, 20)), PayloadMaskThresholds(), &red, &occluder);
  ASSERT_EQ(red.size(), cv::Size(30, 20));
  EXPECT_EQ(cv::countNonZero(red), 30 * 10);
  EXPECT_EQ(cv::countNonZero(occluder), 30 * 10);
}

}  // namespace
}  // namespace hpa
