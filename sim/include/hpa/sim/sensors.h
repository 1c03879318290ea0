#pragma once
// The world's sensors as components: each declares what it measures, its rate, its latency and
// its noise (a SensorDeclaration, the rate table's row), and samples the world after each
// physics step, producing a message the world delivers through one DelayLine per sensor with
// the declared latency. The world owns the list (World::sensors()); `hpa schema rates` prints
// their declarations.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <variant>
#include <vector>

#include "hpa/models/lockstep.h"
#include "hpa/models/sensor_types.h"
#include "hpa/models/state.h"
#include "hpa/sim/payload_camera.h"
#include "hpa/sim/sensor_declaration.h"
#include "hpa/sim/sensor_models.h"

namespace hpa::sim {

struct WorldConfig;

/// What a sensor sees of the world after one physics step: the true state at t_k (the start of
/// the step) and the specific force of that step.
struct SensorInput {
  double t_k_s = 0.0;                                               // time of the sampled state
  const SystemState* state = nullptr;                               // true state at t_k
  Eigen::Vector3d specific_force_B_mps2 = Eigen::Vector3d::Zero();  // R^T (a + g e3) at t_k (3)
};

/// A sample a sensor produced.
using SensorMessage =
    std::variant<ImuSample, GyroSample, VioSample, PayloadDetection, CameraFrame, GripperSample>;

/// A simulated sensor: declares itself and samples the world once per physics step.
class Sensor {
 public:
  virtual ~Sensor() = default;
  /// Its row of the rate table.
  virtual const SensorDeclaration& declaration() const = 0;
  /// Back to its state at World::Reset (its generators re-seeded, its averages emptied).
  virtual void Reset() = 0;
  /// Samples after one physics step; a message captured in it, if the sensor fires.
  virtual std::optional<SensorMessage> Sample(const SensorInput& in) = 0;
  /// When a message it produced was captured (the delivery delay counts from here).
  static double CaptureTime(const SensorMessage& m);
};

/// The IMU (500 Hz): body rate and specific force averaged over its period (a real IMU's
/// decimation filter), white noise and bias random walks from the world's sensor generator.
class ImuSensor final : public Sensor {
 public:
  /// `rng`: the world's sensor generator, shared with VIO (not owned).
  ImuSensor(const WorldConfig& config, std::mt19937_64* rng);
  const SensorDeclaration& declaration() const override { return declaration_; }
  void Reset() override;
  std::optional<SensorMessage> Sample(const SensorInput& in) override;
  /// Its current gyro bias (the rate gyro is the same part).
  const Eigen::Vector3d& gyro_bias_B_radps() const { return model_.gyro_bias_B_radps(); }

 private:
  SensorDeclaration declaration_;
  ImuModel model_;
  int steps_ = 2;  // physics steps per sample
  double dt_s_ = 0.001;
  int count_ = 0;
  Eigen::Vector3d sum_w_B_radps_ = Eigen::Vector3d::Zero();              // (3)
  Eigen::Vector3d sum_specific_force_B_mps2_ = Eigen::Vector3d::Zero();  // (3)
};

/// The gyro PX4's rate loop runs on (the profile's rate_gyro part): the IMU's part averaged at
/// the loop's rate, the IMU's bias, white noise of the same density from a generator of its own
/// (so the IMU's stream is the same with and without it).
class RateGyroSensor final : public Sensor {
 public:
  /// `imu`: the IMU whose bias it shares (not owned).
  RateGyroSensor(const WorldConfig& config, const ImuSensor* imu);
  const SensorDeclaration& declaration() const override { return declaration_; }
  void Reset() override;
  std::optional<SensorMessage> Sample(const SensorInput& in) override;

 private:
  SensorDeclaration declaration_;
  const ImuSensor* imu_;
  uint64_t seed_;
  std::mt19937_64 rng_;
  int steps_ = 1;
  double dt_s_ = 0.001, sigma_radps_ = 0.0;
  int count_ = 0;
  Eigen::Vector3d sum_radps_ = Eigen::Vector3d::Zero();  // (3)
};

/// VIO poses (30 Hz, captured at or after each period's tick): noise from the world's sensor
/// generator, the profile's drift, dropouts and re-localisation.
class VioSensor final : public Sensor {
 public:
  /// `rng`: the world's sensor generator, shared with the IMU (not owned).
  VioSensor(const WorldConfig& config, std::mt19937_64* rng);
  const SensorDeclaration& declaration() const override { return declaration_; }
  void Reset() override;
  std::optional<SensorMessage> Sample(const SensorInput& in) override;
  /// Its drift model (for tests and logs).
  const VioModel& model() const { return model_; }

 private:
  SensorDeclaration declaration_;
  VioModel model_;  // latency 0 inside: the world's delay line delivers it
  VioDriftProfile drift_;
  uint64_t drift_seed_;
  double physics_hz_;
  LockstepClock clock_;
  int loop_ = 0;
};

/// The gripper's switch, read at the start of every tick before its step (an event that grabs or
/// releases at a tick is seen by that tick's flight step), delivered without latency.
class GripperSensor {
 public:
  /// The switch of a world with `config` (its physics rate).
  explicit GripperSensor(const WorldConfig& config);
  /// Its row of the rate table.
  const SensorDeclaration& declaration() const { return declaration_; }
  /// The sample at time_s of a gripper that is `active`.
  GripperSample Sample(double time_s, bool active) const { return {time_s, active}; }

 private:
  SensorDeclaration declaration_;
};

/// The sensors a world with `config` has, in the order it samples them (the rate gyro only with
/// its profile part); throws InputError when a rate does not divide the physics rate into whole
/// steps. `rng` is the world's sensor generator (not owned).
std::vector<std::unique_ptr<Sensor>> MakeSensors(const WorldConfig& config, std::mt19937_64* rng);

/// The rate-table rows of a world with `config`: its sensors', then those read at the start of
/// a tick (the gripper's switch, the payload camera: PayloadCameraSensor), then the wind's.
std::vector<SensorDeclaration> SensorDeclarations(const WorldConfig& config);

}  // namespace hpa::sim
