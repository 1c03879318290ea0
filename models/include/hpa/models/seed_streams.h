#pragma once
// The random streams of a run, each named: one scenario seed, and every generator apart from the
// world's sensor-noise stream seeded from it through its own stream, so that switching one part
// on or off (a mismatch draw, gusts, VIO drift) leaves every other stream's numbers unchanged.

#include <cstdint>

namespace hpa {

/// One named random stream; the value is its salt (ASCII of its name, kept for reproducibility).
enum class SeedStream : uint64_t {
  kMismatch = 0x6D69736D61746368ULL,      // "mismatch": the profile's model-mismatch draw
  kVioDrift = 0x76696FULL,                // "vio": VIO drift, dropouts and re-localisation jumps
  kWind = 0x77696E64ULL,                  // "wind": gusts
  kRateGyro = 0x726174656779ULL,          // "rategy": the rate loop's own gyro noise
  kAppearance = 0x6C69676874ULL,          // "light": randomised lighting and colours
  kCameraImage = 0x63616D657261ULL,       // "camera": the rendered camera's image-noise offsets
  kAnalyticCamera = 17,                   // the analytic camera's detection noise
  kOnboardSensors = 0x6F6E626F617264ULL,  // "onboard": a team vehicle's IMU, VIO and rate gyro
};

/// The seed of `stream` for a run seeded `seed` (a golden-ratio multiplier, then the salt).
constexpr uint64_t DeriveSeed(uint64_t seed, SeedStream stream) {
  return seed * 0x9E3779B97F4A7C15ULL + static_cast<uint64_t>(stream);
}

/// SplitMix64 (Steele, Lea and Flood 2014): a well-mixed 64-bit hash, for independent seeds
/// derived from one (sweep draws, image-noise offsets); the same on every platform.
constexpr uint64_t SplitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

/// The seed of `stream` for vehicle `vehicle` of a team run seeded `seed`: one independent seed
/// per vehicle (the stream's seed plus the vehicle index, mixed by SplitMix64).
constexpr uint64_t DeriveVehicleSeed(uint64_t seed, SeedStream stream, int vehicle) {
  return SplitMix64(DeriveSeed(seed, stream) + static_cast<uint64_t>(vehicle));
}

}  // namespace hpa
