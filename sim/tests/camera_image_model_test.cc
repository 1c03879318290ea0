// The camera image model's shared noise table is the standard library's normal draws, bit for
// bit, however it is computed; its noise is added as the scalar formula says, whichever code
// path adds it; a region's bounds in the render, read off its edges, are the whole region's.
#include "hpa/sim/camera_image_model.h"

#include <gtest/gtest.h>

#include <cstring>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "hpa/models/params.h"

namespace hpa::sim {
namespace {

TEST(CameraImageModelTest, NoiseTableIsTheStandardNormalDrawsBitForBit) {
  const std::vector<float>& table = CameraImageModel::UnitNormalTable();
  ASSERT_GT(table.size(), 2'764'800u);  // more than one 1280 x 720 RGB frame
  std::mt19937_64 rng(0x5eed);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  size_t differing = 0, first_differing = table.size();
  for (size_t i = 0; i < table.size(); ++i) {
    const float expected = normal(rng);
    if (std::memcmp(&expected, &table[i], sizeof(float)) != 0) {
      if (differing++ == 0) first_differing = i;
    }
  }
  EXPECT_EQ(differing, 0u) << "first at index " << first_differing;
}

TEST(CameraImageModelTest, LevelScaledNoiseIsTheScalarFormulaForEveryValue) {
  // every level, noise from the table (and extremes that saturate both ways, ties at .5), in
  // runs of every length 0..67 so that each stretch of a vectorised loop and its tail is used
  std::vector<float> sd(256);
  for (int level = 0; level < 256; ++level) sd[level] = 0.5f + 0.03f * level;
  const std::vector<float>& table = CameraImageModel::UnitNormalTable();
  std::vector<float> unit_normal(table.begin(), table.begin() + 4096);
  for (size_t i = 0; i < unit_normal.size(); i += 97) unit_normal[i] = (i % 2 ? 1e6f : -1e6f);
  for (size_t i = 50; i < unit_normal.size(); i += 89) unit_normal[i] = 0.5f / sd[i % 256];
  std::mt19937_64 rng(7);
  size_t checked = 0;
  for (size_t n = 0; n < 68; ++n) {
    for (size_t start = 0; start + n <= unit_normal.size(); start += 61) {
      std::vector<uint8_t> values(n), expected(n);
      for (size_t i = 0; i < n; ++i) {
        values[i] = static_cast<uint8_t>(rng() % 256);
        expected[i] =
            cv::saturate_cast<uint8_t>(values[i] + sd[values[i]] * unit_normal[start + i]);
      }
      AddLevelScaledNoise(values.data(), sd.data(), unit_normal.data() + start, n);
      ASSERT_EQ(values, expected) << "run of " << n << " at " << start;
      checked += n;
    }
  }
  EXPECT_GT(checked, 100'000u);
}

// The shipped calibration keeps the pixel order (so RenderRegion reads only a region's edges), and
// MapRange on its edges gives cv::minMaxLoc's values over the whole area, for areas of every
// shape across the frame (single rows and columns, the corners, the whole frame).
TEST(CameraImageModelTest, RegionBoundsFromItsEdgesAreTheWholeRegions) {
  const Params params = LoadParams(DefaultParamsPath());
  ASSERT_FALSE(params.camera_distortion.isZero());
  const CameraImageModel model(params, CameraImageProfile(), 1);
  ASSERT_EQ(model.map_x_order(), MapOrder::kIncreasingAlongRows);
  ASSERT_EQ(model.map_y_order(), MapOrder::kIncreasingDownColumns);
  const cv::Mat& map_x = model.map_x();
  const cv::Mat& map_y = model.map_y();
  std::vector<cv::Rect> areas = {cv::Rect(0, 0, map_x.cols, map_x.rows), cv::Rect(0, 0, 1, 1),
                                 cv::Rect(map_x.cols - 1, map_x.rows - 1, 1, 1),
                                 cv::Rect(0, 100, map_x.cols, 1), cv::Rect(700, 0, 1, map_x.rows)};
  std::mt19937_64 rng(3);
  for (int i = 0; i < 2000; ++i) {
    const int w = 1 + static_cast<int>(rng() % 500), h = 1 + static_cast<int>(rng() % 500);
    const int x = static_cast<int>(rng() % (map_x.cols - std::min(w, map_x.cols) + 1));
    const int y = static_cast<int>(rng() % (map_x.rows - std::min(h, map_x.rows) + 1));
    areas.push_back(cv::Rect(x, y, w, h) & cv::Rect(0, 0, map_x.cols, map_x.rows));
  }
  for (const cv::Rect& area : areas) {
    for (const auto& [map, order] : {std::make_pair(&map_x, model.map_x_order()),
                                     std::make_pair(&map_y, model.map_y_order())}) {
      double min_edges, max_edges, min_all, max_all;
      MapRange(*map, area, order, &min_edges, &max_edges);
      cv::minMaxLoc((*map)(area), &min_all, &max_all);
      ASSERT_EQ(min_edges, min_all) << area;
      ASSERT_EQ(max_edges, max_all) << area;
    }
  }
}

// A map out of order anywhere (one value less than its neighbour) is kNone, and is read whole.
TEST(CameraImageModelTest, UnorderedMapIsReadWhole) {
  cv::Mat map(4, 5, CV_32FC1);
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 5; ++c) map.at<float>(r, c) = static_cast<float>(10 * r + c);
  }
  EXPECT_EQ(CheckedMapOrder(map, MapOrder::kIncreasingAlongRows), MapOrder::kIncreasingAlongRows);
  EXPECT_EQ(CheckedMapOrder(map, MapOrder::kIncreasingDownColumns),
            MapOrder::kIncreasingDownColumns);
  map.at<float>(2, 2) = 100.0f;  // an interior maximum: out of order along its row and column
  EXPECT_EQ(CheckedMapOrder(map, MapOrder::kIncreasingAlongRows), MapOrder::kNone);
  EXPECT_EQ(CheckedMapOrder(map, MapOrder::kIncreasingDownColumns), MapOrder::kNone);
  double min_v, max_v;
  MapRange(map, cv::Rect(1, 1, 3, 2), MapOrder::kNone, &min_v, &max_v);
  EXPECT_EQ(min_v, 11.0);
  EXPECT_EQ(max_v, 100.0);
}

}  // namespace
}  // namespace hpa::sim
