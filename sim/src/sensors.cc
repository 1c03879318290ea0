#include "hpa/sim/sensors.h"

#include <cmath>
#include <sstream>
#include <type_traits>

#include "hpa/models/input_error.h"
#include "hpa/models/seed_streams.h"
#include "hpa/sim/wind.h"
#include "hpa/sim/world.h"

namespace hpa::sim {
namespace {

// The IMU noise the world simulates: the profile's IMU part when it has one.
SensorNoiseConfig ImuNoise(const WorldConfig& config) {
  SensorNoiseConfig noise = config.noise;
  if (config.profile.imu.enabled) {
    noise.gyro_noise_density_radps_rthz = config.profile.imu.gyro_noise_density_radps_rthz;
    noise.accel_noise_density_mps2_rthz = config.profile.imu.accel_noise_density_mps2_rthz;
  }
  return noise;
}

std::string Text(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

// Physics steps per sample of a stream that averages whole steps; InputError otherwise.
int WholeSteps(double physics_hz, double rate_hz, const std::string& key, const std::string& what) {
  const double steps = physics_hz / rate_hz;
  if (!(steps >= 1.0) || std::abs(steps - std::round(steps)) > 1e-9) {
    throw InputError("", key, what);
  }
  return static_cast<int>(std::lround(steps));
}

}  // namespace

double Sensor::CaptureTime(const SensorMessage& m) {
  // a rendered frame names its capture time as the flight code reads it
  return std::visit(
      [](const auto& message) {
        if constexpr (std::is_same_v<std::decay_t<decltype(message)>, CameraFrame>) {
          return message.capture_time_s;
        } else {
          return message.time_s;
        }
      },
      m);
}

ImuSensor::ImuSensor(const WorldConfig& config, std::mt19937_64* rng)
    : model_(ImuNoise(config), 1.0 / config.rates.imu.rate_hz, rng),
      dt_s_(1.0 / config.rates.physics_hz) {
  const SensorNoiseConfig noise = ImuNoise(config);
  declaration_ = {"imu", config.rates.imu.rate_hz, config.rates.imu.latency_s,
                  "gyro " + Text(noise.gyro_noise_density_radps_rthz) + " rad/s/sqrt(Hz), accel " +
                      Text(noise.accel_noise_density_mps2_rthz) +
                      " m/s^2/sqrt(Hz), bias random walks",
                  "RateTable::imu; noise: world profile imu"};
  steps_ = WholeSteps(config.rates.physics_hz, config.rates.imu.rate_hz, "rates.imu",
                      "the IMU rate must divide the physics rate");
}

void ImuSensor::Reset() {
  model_.ResetBias();
  sum_w_B_radps_.setZero();
  sum_specific_force_B_mps2_.setZero();
  count_ = 0;
}

std::optional<SensorMessage> ImuSensor::Sample(const SensorInput& in) {
  // the average over its period (a real IMU's internal high-rate sampling and decimation
  // filter): a point sample every other step would alias the 2 ms tension spike of a re-taut
  // into a velocity error of either twice or none of the true impulse
  sum_w_B_radps_ += in.state->w_B;
  sum_specific_force_B_mps2_ += in.specific_force_B_mps2;
  if (++count_ < steps_) return std::nullopt;
  const ImuSample s = model_.Measure(in.t_k_s - dt_s_, sum_w_B_radps_ / count_,
                                     sum_specific_force_B_mps2_ / count_);
  sum_w_B_radps_.setZero();
  sum_specific_force_B_mps2_.setZero();
  count_ = 0;
  return s;
}

RateGyroSensor::RateGyroSensor(const WorldConfig& config, const ImuSensor* imu)
    : imu_(imu),
      seed_(DeriveSeed(config.seed, SeedStream::kRateGyro)),
      rng_(seed_),
      dt_s_(1.0 / config.rates.physics_hz) {
  const double rate_hz = config.profile.rate_gyro.rate_hz;
  declaration_ = {"rate gyro (PX4's rate loop runs on it)", rate_hz, 0.0,
                  "the IMU's gyro noise density and bias at this rate", "rate_loop.rate_hz"};
  steps_ = WholeSteps(config.rates.physics_hz, rate_hz, "world.rate_loop.rate_hz",
                      "the rate must divide the physics rate");
  // discrete white noise of the same density at this rate: sigma = density / sqrt(period)
  sigma_radps_ = ImuNoise(config).gyro_noise_density_radps_rthz / std::sqrt(1.0 / rate_hz);
}

void RateGyroSensor::Reset() {
  rng_.seed(seed_);
  sum_radps_.setZero();
  count_ = 0;
}

std::optional<SensorMessage> RateGyroSensor::Sample(const SensorInput& in) {
  // the same averaging over its own period, the IMU's current bias
  sum_radps_ += in.state->w_B;
  if (++count_ < steps_) return std::nullopt;
  std::normal_distribution<double> unit(0.0, 1.0);
  GyroSample g;
  g.time_s = in.t_k_s - (steps_ - 1) * dt_s_;
  g.gyro_B_radps = sum_radps_ / steps_ + imu_->gyro_bias_B_radps();
  for (int i = 0; i < 3; ++i) g.gyro_B_radps(i) += sigma_radps_ * unit(rng_);
  sum_radps_.setZero();
  count_ = 0;
  return g;
}

VioSensor::VioSensor(const WorldConfig& config, std::mt19937_64* rng)
    : model_(config.noise, 0.0, rng),
      drift_(config.profile.vio),
      drift_seed_(DeriveSeed(config.seed, SeedStream::kVioDrift)),
      physics_hz_(config.rates.physics_hz),
      clock_(config.rates.physics_hz) {
  declaration_ = {"vio", config.rates.vio.rate_hz, config.rates.vio.latency_s,
                  "position " + Text(config.noise.vio_position_sigma_m) + " m, attitude " +
                      Text(config.noise.vio_attitude_sigma_rad) + " rad, velocity " +
                      Text(config.noise.vio_velocity_sigma_mps) + " m/s per sample" +
                      (config.profile.vio.enabled ? "; drift, dropouts and re-localisation" : ""),
                  "RateTable::vio; drift: world profile vio"};
  Reset();
}

void VioSensor::Reset() {
  model_.SetDrift(drift_, drift_seed_);
  clock_ = LockstepClock(physics_hz_);
  loop_ = clock_.AddLoop("vio", declaration_.rate_hz, TickRounding::kAtOrAfter);
}

std::optional<SensorMessage> VioSensor::Sample(const SensorInput& in) {
  // captured at or after each period's tick (the clock ticks once per physics step)
  clock_.BeginTick();
  const bool due = clock_.Fires(loop_);
  clock_.Advance();
  if (!due) return std::nullopt;
  const SystemState& s = *in.state;
  model_.Capture(in.t_k_s, s.p_WQ_W, s.q_WB, s.v_WQ_W);
  const std::optional<VioSample> sample = model_.Take(in.t_k_s);  // none during a dropout
  if (!sample) return std::nullopt;
  return *sample;
}

std::vector<std::unique_ptr<Sensor>> MakeSensors(const WorldConfig& config, std::mt19937_64* rng) {
  std::vector<std::unique_ptr<Sensor>> sensors;
  auto imu = std::make_unique<ImuSensor>(config, rng);
  const ImuSensor* imu_part = imu.get();
  sensors.push_back(std::move(imu));
  if (config.profile.rate_gyro.enabled) {
    sensors.push_back(std::make_unique<RateGyroSensor>(config, imu_part));
  }
  sensors.push_back(std::make_unique<VioSensor>(config, rng));
  return sensors;
}

GripperSensor::GripperSensor(const WorldConfig& config)
    : declaration_{"gripper", config.rates.physics_hz, 0.0, "none (a switch)",
                   "the physics rate; events grab and release"} {}

std::vector<SensorDeclaration> SensorDeclarations(const WorldConfig& config) {
  std::mt19937_64 unused;
  std::vector<SensorDeclaration> rows;
  for (const std::unique_ptr<Sensor>& s : MakeSensors(config, &unused)) {
    rows.push_back(s->declaration());
  }
  rows.push_back(GripperSensor(config).declaration());
  rows.push_back(PayloadCameraSensor(config).declaration());
  rows.push_back(WindModel(config.profile.wind, config.rates.physics_hz, 0).declaration());
  return rows;
}

}  // namespace hpa::sim
