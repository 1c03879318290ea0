#pragma once
// The lockstep clock and the rate table (docs/design.md section 3): one place that says when each
// loop and sensor of the simulated vehicle runs and how late its output arrives. Used by the
// scenario runner, the simulated world and the closed-loop tests alike; no MuJoCo here.

#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "hpa/models/ring_queue.h"

namespace hpa {

/// One periodic stream: how often it fires and how late its output is delivered.
struct StreamRate {
  double rate_hz = 0.0;
  double latency_s = 0.0;  // capture to delivery
};

/// Rates and latencies of the vehicle's loops and sensors, in one table. The high-level
/// controller's rate is its registration's (controller->RateHz()).
struct RateTable {
  double physics_hz = 1000.0;     // MuJoCo step
  StreamRate imu{500.0, 0.0};     // IMU samples and the body-rate loop that runs on them
  StreamRate vio{30.0, 0.02};     // VIO pose (capture to delivery)
  StreamRate camera{30.0, 0.03};  // payload camera frame to detection delivery
  StreamRate video{30.0, 0.0};    // chase-camera video frames
};

/// How the k-th firing time k / rate_hz of a loop maps onto the clock's ticks.
enum class TickRounding {
  kNearest,    // the nearest tick
  kAtOrAfter,  // the first tick at or after it
};

/// A lockstep clock: ticks at tick_hz and the periodic loops that fire on them. Call
/// BeginTick() once per tick, ask Fires(loop) for each loop, then Advance().
class LockstepClock {
 public:
  /// A clock at tick_hz, at tick 0.
  explicit LockstepClock(double tick_hz) : tick_hz_(tick_hz) {}

  /// Registers a loop firing at rate_hz from tick 0; returns its handle for Fires().
  int AddLoop(std::string name, double rate_hz, TickRounding rounding = TickRounding::kNearest) {
    loops_.push_back({std::move(name), rate_hz, rounding, 0, false});
    return static_cast<int>(loops_.size()) - 1;
  }

  /// Works out which loops fire at the current tick.
  void BeginTick() {
    for (Loop& loop : loops_) {
      loop.fires = tick_ == TickOf(loop.next_firing, loop.rate_hz, loop.rounding);
      if (loop.fires) ++loop.next_firing;
    }
  }

  /// True if `loop` fires at the current tick (after BeginTick()).
  bool Fires(int loop) const { return loops_[static_cast<size_t>(loop)].fires; }

  /// Moves to the next tick.
  void Advance() { ++tick_; }

  /// Current tick, from 0.
  long tick() const { return tick_; }
  /// Time of the current tick (s).
  double time_s() const { return tick_ / tick_hz_; }
  /// Tick period (s).
  double dt_s() const { return 1.0 / tick_hz_; }
  /// Name of a loop (for messages).
  const std::string& name(int loop) const { return loops_[static_cast<size_t>(loop)].name; }

  /// Tick of the k-th firing of a loop at rate_hz.
  long TickOf(long k, double rate_hz, TickRounding rounding) const {
    const double at_ticks = k * tick_hz_ / rate_hz;
    // a 1e-9 tick margin keeps an exact multiple from rounding up past itself
    return rounding == TickRounding::kNearest ? static_cast<long>(std::llround(at_ticks))
                                              : static_cast<long>(std::ceil(at_ticks - 1e-9));
  }

 private:
  struct Loop {
    std::string name;
    double rate_hz;
    TickRounding rounding;
    long next_firing;  // k of the next firing
    bool fires;        // at the current tick
  };
  double tick_hz_;
  long tick_ = 0;
  std::vector<Loop> loops_;
};

/// The one latency mechanism of every sensor: items captured at a time are delivered, in
/// capture order, once latency_s has passed on the clock. Its queue reuses its slots: a line in
/// steady state allocates nothing.
template <class T>
class DelayLine {
 public:
  /// Delivers latency_s after capture.
  explicit DelayLine(double latency_s) : latency_s_(latency_s) {}

  /// Queues an item captured at capture_time_s.
  void Push(double capture_time_s, T item) {
    queue_.push_back(std::make_pair(capture_time_s, std::move(item)));
  }

  /// The oldest item whose delivery time (capture + latency) is at or before now_s, if any.
  std::optional<T> PopReady(double now_s) {
    // a 1 ns margin keeps the delivery time robust to floating-point rounding of the clock
    constexpr double kRoundingMargin_s = 1e-9;
    if (queue_.empty() || queue_.front().first + latency_s_ > now_s + kRoundingMargin_s) {
      return std::nullopt;
    }
    T item = std::move(queue_.front().second);
    queue_.pop_front();
    return item;
  }

  /// Drops everything queued.
  void Clear() {
    while (size() > 0) DropOldest();
  }
  /// Drops the oldest item (a bounded queue whose reader fell behind).
  void DropOldest() {
    if (queue_.empty()) return;
    [[maybe_unused]] const T dropped =
        std::move(queue_.front().second);  // the slot keeps none of it
    queue_.pop_front();
  }
  /// Items waiting.
  size_t size() const { return queue_.size(); }
  double latency_s() const { return latency_s_; }

 private:
  double latency_s_;
  RingQueue<std::pair<double, T>> queue_;  // (capture time, item), oldest first
};

}  // namespace hpa
