#pragma once
// A simulated sensor's row of the rate table (sensors.h, payload_camera.h).

#include <string>

namespace hpa::sim {

/// One simulated sensor stream as the world declares it: what it measures, how often, how late it
/// is delivered and its noise. The world samples each stream at this rate and delivers it
/// through a DelayLine of this latency; `hpa schema rates` prints these rows.
struct SensorDeclaration {
  std::string name;        // "imu", "rate gyro", "vio", "payload camera"
  double rate_hz = 0.0;    // samples per second (the physics rate divides into whole steps)
  double latency_s = 0.0;  // capture to delivery
  std::string noise;       // its noise, one line with units
  std::string from;        // where the rate and latency are set
};

}  // namespace hpa::sim
