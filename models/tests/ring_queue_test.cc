// RingQueue: a queue in order across the ring's wrap and its growth, searched by std::upper_bound.
#include "hpa/models/ring_queue.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <deque>

namespace hpa {
namespace {

// The ring against std::deque through pushes and pops that wrap it and make it grow.
TEST(RingQueueTest, KeepsTheOrderOfADequeAcrossWrapAndGrowth) {
  RingQueue<int> ring;
  std::deque<int> expected;
  int next = 0;
  for (int round = 0; round < 200; ++round) {
    const int pushes = 1 + round % 7, pops = round % 5;  // the ring grows past 16, then 32, ...
    for (int i = 0; i < pushes; ++i) {
      ring.push_back(next);
      expected.push_back(next++);
    }
    for (int i = 0; i < pops && !expected.empty(); ++i) {
      ring.pop_front();
      expected.pop_front();
    }
    ASSERT_EQ(ring.size(), expected.size());
    for (size_t i = 0; i < expected.size(); ++i) ASSERT_EQ(ring[i], expected[i]) << i;
    if (!expected.empty()) {
      ASSERT_EQ(ring.front(), expected.front());
      ASSERT_EQ(ring.back(), expected.back());
    }
  }
  ring.clear();
  EXPECT_TRUE(ring.empty());
  EXPECT_EQ(ring.begin(), ring.end());
}

// std::upper_bound over a wrapped ring finds what it finds in a deque of the same values.
TEST(RingQueueTest, UpperBoundSearchesTheWrappedRing) {
  RingQueue<double> ring;
  std::deque<double> expected;
  for (int i = 0; i < 40; ++i) {
    ring.push_back(0.1 * i);
    expected.push_back(0.1 * i);
    if (i >= 10) {
      ring.pop_front();
      expected.pop_front();
    }
  }
  for (double t = 2.0; t < 4.2; t += 0.05) {
    const auto it = std::upper_bound(ring.begin(), ring.end(), t);
    const auto want = std::upper_bound(expected.begin(), expected.end(), t);
    EXPECT_EQ(it - ring.begin(), want - expected.begin()) << t;
  }
}

}  // namespace
}  // namespace hpa
