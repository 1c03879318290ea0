// SensorSuite: a vehicle's sensors, sampled each step, delivered after their latency through
// the vehicle's faults.

#include "hpa/sim/sensor_suite.h"

#include <utility>

#include "hpa/sim/faults.h"
#include "hpa/sim/world.h"

namespace hpa::sim {

SensorSuite::SensorSuite(const WorldConfig& config)
    : seed_(config.seed), rng_(config.seed), sensors_(MakeSensors(config, &rng_)) {
  // each sensor's output reaches its reader after the latency it declares
  for (const std::unique_ptr<Sensor>& sensor : sensors_) {
    sensor_lines_.push_back(AddLine(sensor->declaration().latency_s));
  }
}

int SensorSuite::AddLine(double latency_s) {
  lines_.emplace_back(latency_s);
  return static_cast<int>(lines_.size()) - 1;
}

void SensorSuite::Push(int line, double capture_time_s, SensorMessage message) {
  lines_[static_cast<size_t>(line)].Push(capture_time_s, std::move(message));
}

void SensorSuite::AddSensor(std::unique_ptr<Sensor> sensor) {
  sensor->Reset();
  sensor_lines_.push_back(AddLine(sensor->declaration().latency_s));
  sensors_.push_back(std::move(sensor));
}

void SensorSuite::Sample(const SensorInput& in) {
  for (size_t i = 0; i < sensors_.size(); ++i) {
    if (std::optional<SensorMessage> m = sensors_[i]->Sample(in)) {
      DelayLine<SensorMessage>& line = lines_[static_cast<size_t>(sensor_lines_[i])];
      line.Push(Sensor::CaptureTime(*m), std::move(*m));
      if (line.size() > kMaxQueued) line.DropOldest();
    }
  }
}

void SensorSuite::TakeDelivered(double now_s, Faults* faults, std::vector<SensorMessage>* out) {
  out->clear();
  for (DelayLine<SensorMessage>& line : lines_) {
    while (std::optional<SensorMessage> m = line.PopReady(now_s)) out->push_back(std::move(*m));
  }
  if (faults != nullptr && !faults->empty()) faults->FilterDelivered(now_s, out);
}

std::vector<SensorMessage> SensorSuite::TakeInFlight(double now_s, Faults* faults) {
  std::vector<SensorMessage> out;
  for (DelayLine<SensorMessage>& line : lines_) {
    while (std::optional<SensorMessage> m = line.PopReady(1e300)) out.push_back(std::move(*m));
  }
  if (faults != nullptr && !faults->empty()) {
    faults->FilterDelivered(now_s, &out);
    faults->TakeHeld(&out);
  }
  return out;
}

void SensorSuite::Reset() {
  rng_.seed(seed_);
  for (const std::unique_ptr<Sensor>& sensor : sensors_) sensor->Reset();
  for (DelayLine<SensorMessage>& line : lines_) line.Clear();
}

}  // namespace hpa::sim
