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
  // OpenCV's saturation and hue of one pixel against the red bands: 255 or 0
  const auto exact_red = [&](const uint8_t* px) -> uint8_t {
    const int b = px[0], g = px[1], r = px[2];
    const int v = std::max({b, g, r});
    const int diff = v - std::min({b, g, r});
    if (v < v_min) return 0;
    const int s = (diff * tables.saturation_div[v] + round) >> kHsvShift;
    if (s < s_min) return 0;
    // the hue by the channel that holds the maximum (red first, then green)
    int h = v == r ? g - b : v == g ? b - r + 2 * diff : r - g + 4 * diff;
    h = (h * tables.hue_div[diff] + round) >> kHsvShift;
    h = std::min(h + (h < 0 ? 180 : 0), 255);
    return (h <= thresholds.hue_max_low || (h >= thresholds.hue_min_high && h <= 180)) ? 255 : 0;
  };
  // the vector pass holds its thresholds in bytes (and s_min - 1 in 16 bits)
  const bool vector_pass =
      v_min >= 0 && v_min <= 255 && dark_max >= 0 && dark_max <= 255 && s_min <= 256;
  for (int row = 0; row < bgr.rows; ++row) {
    const uint8_t* p = bgr.ptr<uint8_t>(row);
    uint8_t* red_row = red->ptr<uint8_t>(row);
    uint8_t* dark_row = occluder->ptr<uint8_t>(row);
    int col = 0;
#if CV_SIMD128
    // sixteen pixels at a time: the occluders, and whether any pixel's value passes and its
    // saturation can (at least s_min needs diff * 255 > (s_min - 1) * v: OpenCV's rounded table
    // adds less than 0.6 to diff * 255 / v; both sides fit in 16 bits); the exact test runs only
    // on such a block (the payload's pixels, a few of the floor's)
    const cv::v_uint8x16 dark_max_x = cv::v_setall_u8(static_cast<uint8_t>(dark_max));
    const cv::v_uint8x16 v_min_x = cv::v_setall_u8(static_cast<uint8_t>(v_min));
    const cv::v_uint16x8 k255 = cv::v_setall_u16(255);
    const cv::v_uint16x8 s_bound_x =
        cv::v_setall_u16(static_cast<uint16_t>(std::max(s_min - 1, 0)));
    for (; vector_pass && col + 16 <= bgr.cols; col += 16) {
      cv::v_uint8x16 b, g, r;
      cv::v_load_deinterleave(p + 3 * col, b, g, r);
      const cv::v_uint8x16 v = cv::v_max(cv::v_max(b, g), r);
      const cv::v_uint8x16 diff = v - cv::v_min(cv::v_min(b, g), r);
      cv::v_store(dark_row + col, v <= dark_max_x);
      cv::v_uint8x16 candidate = v >= v_min_x;
      if (s_min > 0) {
        cv::v_uint16x8 diff_lo, diff_hi, v_lo, v_hi;
        cv::v_expand(diff, diff_lo, diff_hi);
        cv::v_expand(v, v_lo, v_hi);
        const cv::v_uint16x8 lo = (diff_lo * k255) > (v_lo * s_bound_x);
        const cv::v_uint16x8 hi = (diff_hi * k255) > (v_hi * s_bound_x);
        candidate = candidate & cv::v_pack(lo, hi);  // 0xffff saturates to 0xff
      }
      if (!cv::v_check_any(candidate)) {
        cv::v_store(red_row + col, cv::v_setzero_u8());
        continue;
      }
      for (int k = col; k < col + 16; ++k) red_row[k] = exact_red(p + 3 * k);
    }
#endif
    for (; col < bgr.cols; ++col) {
      dark_row[col] = std::max({p[3 * col], p[3 * col + 1], p[3 * col + 2]}) <= dark_max ? 255 : 0;
      red_row[col] = exact_red(p + 3 * col);
    }
  }
}

}  // namespace hpa
