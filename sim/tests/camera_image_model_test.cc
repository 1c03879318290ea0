// The camera image model's shared noise table is the standard library's normal draws, bit for
// bit, however it is computed.
#include "hpa/sim/camera_image_model.h"

#include <gtest/gtest.h>

#include <cstring>
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

}  // namespace
}  // namespace hpa::sim
