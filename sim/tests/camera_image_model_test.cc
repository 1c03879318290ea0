// The camera image model's shared noise table is the standard library's normal draws, bit for
// bit, however it is computed; its noise is added as the scalar formula says, whichever code
// path adds it.
#include "hpa/sim/camera_image_model.h"

#include <gtest/gtest.h>

#include <cstring>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

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

}  // namespace
}  // namespace hpa::sim
