#pragma once
// One vehicle's onboard sensors and their delivery, a component of sim::World and of each of
// sim::TeamWorld's vehicles: the sensors MakeSensors builds (IMU, the rate gyro with its profile
// part, VIO) with their own noise generator, one DelayLine per sensor of its declared latency,
// the lines its world pushes into itself (the gripper's switch, the payload camera), and the
// vehicle's Faults applied on delivery. The world builds each step's SensorInput; the suite
// samples, queues and delivers.

#include <cstdint>
#include <memory>
#include <random>
#include <vector>

#include "hpa/models/lockstep.h"
#include "hpa/sim/sensors.h"

namespace hpa::sim {

class Faults;
struct WorldConfig;

/// A vehicle's sensors, their delay lines and their delivery through the vehicle's faults.
class SensorSuite {
 public:
  /// The sensors of a vehicle of `config` (MakeSensors), their generator seeded with config.seed;
  /// throws InputError as MakeSensors does.
  explicit SensorSuite(const WorldConfig& config);
  SensorSuite(const SensorSuite&) = delete;
  SensorSuite& operator=(const SensorSuite&) = delete;

  /// The sensors, in the order they are sampled and delivered.
  const std::vector<std::unique_ptr<Sensor>>& sensors() const { return sensors_; }
  /// A line the world pushes into itself (not sampled), delivered latency_s after each message's
  /// capture, after every line so far; its index for Push.
  int AddLine(double latency_s);
  /// Queues `message`, captured at capture_time_s, on line `line` (an AddLine index).
  void Push(int line, double capture_time_s, SensorMessage message);
  /// Adds a sensor (Reset first) after the others, its line after every line so far.
  void AddSensor(std::unique_ptr<Sensor> sensor);

  /// Samples every sensor on one physics step's input and queues what each produced on its line
  /// (a line keeps at most kMaxQueued messages, the oldest dropped, if its reader never takes
  /// them).
  void Sample(const SensorInput& in);
  /// Every message whose latency has passed at now_s, line by line in capture order, into `out`
  /// (cleared first, its memory kept), then through `faults` (null or empty: none).
  void TakeDelivered(double now_s, Faults* faults, std::vector<SensorMessage>* out);
  /// Every message still in a line (the end of a run), line by line in capture order, through
  /// `faults` (null or empty: none) with the messages it holds back.
  std::vector<SensorMessage> TakeInFlight(double now_s, Faults* faults);
  /// Back to the start: the generator re-seeded, every sensor Reset, every line emptied.
  void Reset();

  /// Most messages one sampled line keeps: 2 s of IMU samples.
  static constexpr size_t kMaxQueued = 1000;

 private:
  uint64_t seed_;        // the generator's seed (config.seed)
  std::mt19937_64 rng_;  // the IMU's and VIO's noise (their sensors point to it)
  std::vector<std::unique_ptr<Sensor>> sensors_;
  std::vector<DelayLine<SensorMessage>> lines_;  // one per sensor, then the pushed ones
  std::vector<int> sensor_lines_;                // each of sensors_'s place in lines_
};

}  // namespace hpa::sim
