#include "hpa/models/seed_streams.h"

#include <gtest/gtest.h>

#include <set>

namespace hpa {
namespace {

TEST(SeedStreamsTest, SplitMix64MatchesTheReferenceSequence) {
  // the first outputs of Vigna's splitmix64.c from state 0 (each call adds the constant first)
  EXPECT_EQ(SplitMix64(0), 0xE220A8397B1DCDAFULL);
  EXPECT_EQ(SplitMix64(0x9E3779B97F4A7C15ULL), 0x6E789E6AA1B965F4ULL);
}

TEST(SeedStreamsTest, StreamsAreDistinctAndKeepTheirValues) {
  const SeedStream all[] = {SeedStream::kMismatch,      SeedStream::kVioDrift,
                            SeedStream::kWind,          SeedStream::kRateGyro,
                            SeedStream::kAppearance,    SeedStream::kCameraImage,
                            SeedStream::kAnalyticCamera};
  std::set<uint64_t> seeds;
  for (SeedStream s : all) seeds.insert(DeriveSeed(7, s));
  EXPECT_EQ(seeds.size(), std::size(all));
  // a changed salt changes every run of the stream: the recorded golden metrics depend on these
  EXPECT_EQ(DeriveSeed(1, SeedStream::kWind), 0x9E3779B97F4A7C15ULL + 0x77696E64ULL);
  EXPECT_EQ(DeriveSeed(2, SeedStream::kAnalyticCamera), 2 * 0x9E3779B97F4A7C15ULL + 17);
}

}  // namespace
}  // namespace hpa
