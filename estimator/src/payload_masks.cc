#include "hpa/estimator/payload_masks.h"

#include <algorithm>
#include <array>
#include <opencv2/core/hal/intrin.hpp>

namespace hpa {
namespace {

constexpr int kHsvShift = 12;  // OpenCV's fixed-point shift for 8-bit HSV

// OpenCV's 8-bit HSV division tables: saturation 255 / v and hue 180 / (6 diff), each scaled by
// 2^12 and rounded as cv::saturate_cast<int> rounds a double.
struct HsvTables {
  std::array<int, 256> saturation_div{};
  std::array<int, 256> hue_div{};
  HsvTables() {
    for (int i = 1; i < 256; ++i) {
      saturation_div[i] = cvRound((255 << kHsvShift) / (1.0 * i));
      hue_div[i] = cvRound((180 << kHsvShift) / (6.0 * i));
    }
  }
};

const HsvTables& Tables() {
  static const HsvTables tables;
  return tables;
}

}  // namespace

void PayloadMasks(const cv::Mat& bgr, const PayloadMaskThresholds& thresholds, cv::Mat* red,
                  cv::Mat* occluder) {
  CV_Assert(bgr.type() == CV_8UC3);
  red->create(bgr.size(), CV_8UC1);
  occluder->create(bgr.size(), CV_8UC1);
  const HsvTables& tables = Tables();
  const int round = 1 << (kHsvShift - 1);
  const int s_min = thresholds.saturation_min, v_min = thresholds.value_min;
  const int dark_max = thresholds.occluder_value_max;
  // a saturation of at least s_min needs diff * 255 > (s_min - 1) * v (OpenCV's rounded table
  // adds less than 0.6 to diff * 255 / v): the first pass marks the pixels that pass that and the
  // value threshold, and the occluders, with integer operations, sixteen pixels at a time; the
  // second computes the exact saturation and hue of the marked ones (the payload's pixels, a few
  // of the floor's)
  const int s_bound = s_min - 1;
  const int any_saturation = s_min <= 0 ? 1 : 0;  // every pixel's saturation passes
  for (int row = 0; row < bgr.rows; ++row) {
    const uint8_t* p = bgr.ptr<uint8_t>(row);
    uint8_t* red_row = red->ptr<uint8_t>(row);
    uint8_t* dark_row = occluder->ptr<uint8_t>(row);
    int col = 0;
#if CV_SIMD128
    // sixteen pixels at a time: the same integer tests (diff * 255 and s_bound * v fit in 16 bits)
    const cv::v_uint8x16 dark_max_x = cv::v_setall_u8(static_cast<uint8_t>(dark_max));
    const cv::v_uint8x16 v_min_x = cv::v_setall_u8(static_cast<uint8_t>(v_min));
    const cv::v_uint16x8 k255 = cv::v_setall_u16(255);
    const cv::v_uint16x8 s_bound_x = cv::v_setall_u16(static_cast<uint16_t>(std::max(s_bound, 0)));
    for (; col + 16 <= bgr.cols; col += 16) {
      cv::v_uint8x16 b, g, r;
      cv::v_load_deinterleave(p + 3 * col, b, g, r);
      const cv::v_uint8x16 v = cv::v_max(cv::v_max(b, g), r);
      const cv::v_uint8x16 diff = v - cv::v_min(cv::v_min(b, g), r);
      cv::v_store(dark_row + col, v <= dark_max_x);
      cv::v_uint8x16 candidate = v >= v_min_x;
      if (!any_saturation) {
        cv::v_uint16x8 diff_lo, diff_hi, v_lo, v_hi;
        cv::v_expand(diff, diff_lo, diff_hi);
        cv::v_expand(v, v_lo, v_hi);
        const cv::v_uint16x8 lo = (diff_lo * k255) > (v_lo * s_bound_x);
        const cv::v_uint16x8 hi = (diff_hi * k255) > (v_hi * s_bound_x);
        candidate = candidate & cv::v_pack(lo, hi);  // 0xffff saturates to 0xff
      }
      cv::v_store(red_row + col, candidate);
    }
#endif
    for (; col < bgr.cols; ++col) {
      const int b = p[3 * col], g = p[3 * col + 1], r = p[3 * col + 2];
      const int v = std::max(std::max(b, g), r);
      const int diff = v - std::min(std::min(b, g), r);
      dark_row[col] = v <= dark_max ? 255 : 0;
      red_row[col] = (v >= v_min) & (any_saturation | (diff * 255 > s_bound * v)) ? 255 : 0;
    }
    for (int col = 0; col < bgr.cols; ++col) {
      if (red_row[col] == 0) continue;
      const int b = p[3 * col], g = p[3 * col + 1], r = p[3 * col + 2];
      const int v = std::max({b, g, r});
      const int diff = v - std::min({b, g, r});
      const int s = (diff * tables.saturation_div[v] + round) >> kHsvShift;
      uint8_t is_red = 0;
      if (s >= s_min) {
        // OpenCV's hue: by the channel that holds the maximum (red first, then green)
        int h = v == r ? g - b : v == g ? b - r + 2 * diff : r - g + 4 * diff;
        h = (h * tables.hue_div[diff] + round) >> kHsvShift;
        h = std::min(h + (h < 0 ? 180 : 0), 255);
        is_red =
            (h <= thresholds.hue_max_low || (h >= thresholds.hue_min_high && h <= 180)) ? 255 : 0;
      }
      red_row[col] = is_red;
    }
  }
}

}  // namespace hpa
