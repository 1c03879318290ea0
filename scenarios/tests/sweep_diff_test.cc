// sweep-diff statistics against textbook values (R: mcnemar exact = binom.test on the
// discordant pairs; wilcox.test(x, exact = TRUE)).

#include "hpa/scenarios/sweep_diff.h"

#include <gtest/gtest.h>

#include <cmath>

namespace hpa {
namespace {

TEST(SweepDiffTest, McNemarExactMatchesTheBinomialTest) {
  EXPECT_DOUBLE_EQ(McNemarPValue(0, 0), 1.0);
  EXPECT_NEAR(McNemarPValue(0, 10), 2.0 / 1024.0, 1e-12);         // binom.test(0, 10)
  EXPECT_NEAR(McNemarPValue(3, 7), 2.0 * 176.0 / 1024.0, 1e-12);  // binom.test(3, 10)
  EXPECT_DOUBLE_EQ(McNemarPValue(5, 5), 1.0);
}

TEST(SweepDiffTest, SignedRankExactMatchesR) {
  EXPECT_NEAR(SignedRankPValue({1, 2, 3, 4, 5, 6, 7, 8, 9, 10}), 2.0 / 1024.0, 1e-12);
  EXPECT_NEAR(SignedRankPValue({1, -2, 3, -4, 5}), 0.8125, 1e-12);  // V = 9
  EXPECT_DOUBLE_EQ(SignedRankPValue({0, 0, 0}), 1.0);               // all ties at zero
}

TEST(SweepDiffTest, SignedRankNormalApproximationForLargeSamples) {
  std::vector<double> shifted, symmetric;
  for (int i = 1; i <= 40; ++i) {
    shifted.push_back(i % 5 == 0 ? -0.1 * i : 0.1 * i);  // mostly positive
    symmetric.push_back(i % 2 ? 0.1 * i : -0.1 * i);
  }
  // W+ = 820 - 180 = 640, mean 410, var 40 * 41 * 81 / 24: z = (230 - 0.5) / sqrt(5535)
  EXPECT_NEAR(SignedRankPValue(shifted), std::erfc((229.5 / std::sqrt(5535.0)) / std::sqrt(2.0)),
              1e-12);
  EXPECT_GT(SignedRankPValue(symmetric), 0.5);
}

TEST(SweepDiffTest, BootstrapIntervalCoversTheMeanAndIsDeterministic) {
  const std::vector<double> d = {0.1, 0.2, 0.15, 0.3, 0.05, 0.25, 0.2, 0.1};
  const auto ci = BootstrapMeanCi(d);
  EXPECT_LT(ci.first, 0.16875);
  EXPECT_GT(ci.second, 0.16875);
  EXPECT_GT(ci.first, 0.0);  // every difference positive
  EXPECT_EQ(ci, BootstrapMeanCi(d));
  const auto zero = BootstrapMeanCi({0, 0, 0});
  EXPECT_EQ(zero.first, 0.0);
  EXPECT_EQ(zero.second, 0.0);
}

}  // namespace
}  // namespace hpa
