#include "hpa/models/lockstep.h"

#include <gtest/gtest.h>

#include <vector>

namespace hpa {
namespace {

// The ticks (of a 1 kHz clock, over `ticks` ticks) at which a loop at rate_hz fires.
std::vector<long> FiringTicks(double rate_hz, TickRounding rounding, long ticks) {
  LockstepClock clock(1000.0);
  const int loop = clock.AddLoop("loop", rate_hz, rounding);
  std::vector<long> fired;
  for (long k = 0; k < ticks; ++k, clock.Advance()) {
    clock.BeginTick();
    if (clock.Fires(loop)) fired.push_back(clock.tick());
  }
  return fired;
}

TEST(LockstepClockTest, LoopsFireAtTheirRateOnTheNearestOrNextTick) {
  // 150 Hz on 1 kHz: 150 firings a second, 6 or 7 ticks apart, at round(k * 6.667)
  const std::vector<long> mpc = FiringTicks(150.0, TickRounding::kNearest, 1000);
  ASSERT_EQ(mpc.size(), 150u);
  EXPECT_EQ(mpc[0], 0);
  EXPECT_EQ(mpc[1], 7);
  EXPECT_EQ(mpc[2], 13);
  EXPECT_EQ(mpc[3], 20);
  // 30 Hz at or after: ceil(k * 33.33): 0, 34, 67, 100
  const std::vector<long> vio = FiringTicks(30.0, TickRounding::kAtOrAfter, 101);
  EXPECT_EQ(vio, (std::vector<long>{0, 34, 67, 100}));
  // an exact divisor fires on its multiples under both roundings
  EXPECT_EQ(FiringTicks(500.0, TickRounding::kNearest, 7), (std::vector<long>{0, 2, 4, 6}));
  EXPECT_EQ(FiringTicks(500.0, TickRounding::kAtOrAfter, 7), (std::vector<long>{0, 2, 4, 6}));
}

TEST(LockstepClockTest, TimeFollowsTheTicks) {
  LockstepClock clock(1000.0);
  for (int k = 0; k < 250; ++k) clock.Advance();
  EXPECT_EQ(clock.tick(), 250);
  EXPECT_DOUBLE_EQ(clock.time_s(), 0.25);
  EXPECT_DOUBLE_EQ(clock.dt_s(), 0.001);
}

TEST(DelayLineTest, DeliversInCaptureOrderOnceTheLatencyHasPassed) {
  DelayLine<int> line(0.03);
  line.Push(0.0, 1);
  line.Push(0.01, 2);
  EXPECT_FALSE(line.PopReady(0.029).has_value());
  EXPECT_EQ(line.PopReady(0.03), 1);  // exactly at capture + latency (clock rounding absorbed)
  EXPECT_FALSE(line.PopReady(0.0399).has_value());
  EXPECT_EQ(line.PopReady(0.05), 2);
  EXPECT_EQ(line.size(), 0u);
  // a later item never overtakes an earlier one
  line.Push(0.1, 3);
  line.Push(0.1, 4);
  EXPECT_EQ(line.PopReady(1.0), 3);
  EXPECT_EQ(line.PopReady(1.0), 4);
  line.Push(2.0, 5);
  line.Clear();
  EXPECT_FALSE(line.PopReady(10.0).has_value());
  // zero latency: delivered at its own capture time
  DelayLine<int> now(0.0);
  now.Push(0.5, 6);
  EXPECT_EQ(now.PopReady(0.5), 6);
}

}  // namespace
}  // namespace hpa
