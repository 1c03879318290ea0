#include "hpa/estimator/payload_masks.h"

#include <algorithm>
#include <array>

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
  for (int row = 0; row < bgr.rows; ++row) {
    const uint8_t* p = bgr.ptr<uint8_t>(row);
    uint8_t* red_row = red->ptr<uint8_t>(row);
    uint8_t* dark_row = occluder->ptr<uint8_t>(row);
    for (int col = 0; col < bgr.cols; ++col, p += 3) {
      const int b = p[0], g = p[1], r = p[2];
      const int v = std::max({b, g, r});
      const int diff = v - std::min({b, g, r});
      dark_row[col] = v <= dark_max ? 255 : 0;
      uint8_t is_red = 0;
      if (v >= v_min) {
        const int s = (diff * tables.saturation_div[v] + round) >> kHsvShift;
        if (s >= s_min) {
          // OpenCV's hue: by the channel that holds the maximum (red first, then green)
          int h = v == r ? g - b : v == g ? b - r + 2 * diff : r - g + 4 * diff;
          h = (h * tables.hue_div[diff] + round) >> kHsvShift;
          h = std::min(h + (h < 0 ? 180 : 0), 255);
          is_red =
              (h <= thresholds.hue_max_low || (h >= thresholds.hue_min_high && h <= 180)) ? 255 : 0;
        }
      }
      red_row[col] = is_red;
    }
  }
}

}  // namespace hpa
