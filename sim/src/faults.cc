// The fault component: the declaration of every component and mode, and their effects on the
// delivered sensor messages, the camera's captures, the motors and the gripper.

#include "hpa/sim/faults.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <type_traits>
#include <utility>
#include <variant>

#include "hpa/models/camera_model.h"
#include "hpa/models/seed_streams.h"

namespace hpa::sim {
namespace {

// The salt of the faults' streams ("fault"), beside models/seed_streams.h's named streams.
constexpr uint64_t kFaultSalt = 0x6661756C74ULL;

FaultKeyDecl Number(std::string key, std::string unit, std::string description, double min,
                    double max, std::optional<double> fallback, double Fault::*field,
                    bool integer = false) {
  return {std::move(key), std::move(unit), std::move(description), min, max, fallback, field,
          nullptr,        integer};
}

FaultKeyDecl Vector(std::string key, std::string unit, std::string description, double min,
                    double max, std::optional<double> fallback, Eigen::Vector3d Fault::*field) {
  return {
      std::move(key), std::move(unit), std::move(description), min, max, fallback, nullptr, field,
      false};
}

// The modes every sensor stream shares.
FaultModeDecl Off(const std::string& px4) {
  return {FaultMode::kOff, "off", px4, "no samples at all", {}};
}
FaultModeDecl Stuck(const std::string& px4, const std::string& what) {
  return {FaultMode::kStuck,
          "stuck",
          px4,
          "the first " + what +
              " of the fault, again and again "
              "(each with its own time stamp)",
          {}};
}
FaultModeDecl Delayed(const std::string& px4) {
  return {FaultMode::kDelayed,
          "delayed",
          px4,
          "each sample delivered `delay` s later than declared (none overtakes another)",
          {Number("delay", "s", "extra latency", 0.001, 2.0, std::nullopt, &Fault::delay_s)}};
}
FaultModeDecl Slow(const std::string& px4) {
  return {FaultMode::kSlow,
          "slow",
          px4,
          "samples kept at `rate` Hz at most (the others dropped)",
          {Number("rate", "Hz", "the lower rate", 0.1, 1000.0, std::nullopt, &Fault::rate_hz)}};
}
FaultModeDecl Intermittent(const std::string& px4) {
  return {FaultMode::kIntermittent,
          "intermittent",
          px4,
          "each sample dropped with probability `drop_rate` (the fault's seeded stream)",
          {Number("drop_rate", "1", "share of samples dropped", 0.0, 1.0, std::nullopt,
                  &Fault::drop_fraction)}};
}
FaultKeyDecl GyroBias() {
  return Vector("gyro_bias", "rad/s", "added to every gyro sample (body frame)", -10.0, 10.0, 0.0,
                &Fault::gyro_bias_B_radps);
}
FaultKeyDecl GyroNoise() {
  return Number("gyro_noise", "rad/s", "standard deviation added per sample and axis", 0.0, 10.0,
                0.0, &Fault::gyro_noise_radps);
}

// The VIO stream's faults.
FaultComponentDecl VioComponent() {
  return {FaultComponent::kVio,
          "vio",
          "visual-inertial odometry (the VioSample stream)",
          {Off("failure vio off"),
           Stuck("failure vio stuck", "pose"),
           {FaultMode::kWrong,
            "wrong",
            "failure vio wrong",
            "position jumped by `offset` while the fault lasts",
            {Vector("offset", "m", "added to the position (world frame)", -100.0, 100.0,
                    std::nullopt, &Fault::offset_W_m)}},
           Delayed("failure vio delayed"),
           Slow("failure vio slow"),
           Intermittent("failure vio intermittent")}};
}

// The IMU's faults.
FaultComponentDecl ImuComponent() {
  return {FaultComponent::kImu,
          "imu",
          "the IMU (gyro and accelerometer, the estimator's prediction)",
          {Stuck("failure gyro stuck; failure accel stuck", "sample"),
           {FaultMode::kBias,
            "bias",
            "failure gyro wrong; failure accel wrong",
            "a bias step on the gyro and the accelerometer",
            {GyroBias(), Vector("accel_bias", "m/s^2",
                                "added to every specific force sample (body "
                                "frame)",
                                -100.0, 100.0, 0.0, &Fault::accel_bias_B_mps2)}},
           {FaultMode::kNoise,
            "noise",
            "failure gyro garbage; failure accel garbage",
            "a burst of white noise on the gyro and the accelerometer",
            {GyroNoise(), Number("accel_noise", "m/s^2",
                                 "standard deviation added per sample and "
                                 "axis",
                                 0.0, 100.0, 0.0, &Fault::accel_noise_mps2)}}}};
}

// The rate loop gyro's faults.
FaultComponentDecl RateGyroComponent() {
  return {FaultComponent::kRateGyro,
          "rate_gyro",
          "the rate loop's gyro (PX4's rate controller flies on it)",
          {Stuck("failure gyro stuck", "sample"),
           {FaultMode::kBias, "bias", "failure gyro wrong", "a gyro bias step", {GyroBias()}},
           {FaultMode::kNoise,
            "noise",
            "failure gyro garbage",
            "a burst of white gyro noise",
            {GyroNoise()}}}};
}

// A rotor's faults.
FaultComponentDecl MotorComponent() {
  const FaultKeyDecl motor = Number("motor", "1", "rotor index (PX4's -i, counted from 0)", 0, 3,
                                    std::nullopt, &Fault::motor, true);
  return {
      FaultComponent::kMotor,
      "motor",
      "one rotor's thrust (and its yaw torque with it)",
      {{FaultMode::kLoss,
        "loss",
        "",
        "loss of effectiveness: the rotor gives (1 - `loss`) of its thrust",
        {motor,
         Number("loss", "1", "share of thrust lost, 0-1", 0.0, 1.0, std::nullopt, &Fault::loss)}},
       {FaultMode::kOff, "off", "failure motor off -i N", "the rotor gives no thrust", {motor}}}};
}

// The gripper's faults.
FaultComponentDecl GripperComponent() {
  return {FaultComponent::kGripper,
          "gripper",
          "the gripper holding the payload (the test rig's hand)",
          {{FaultMode::kEarly, "early", "", "lets the payload go at `at` on its own", {}, false},
           {FaultMode::kLate,
            "late",
            "",
            "a release commanded in the fault's window happens at its end",
            {}}}};
}

// The payload camera's faults.
FaultComponentDecl CameraComponent() {
  return {
      FaultComponent::kCamera,
      "payload_camera",
      "the payload camera (its detections in process, its frames for a separate stack)",
      {Off(""),
       Stuck("", "frame"),
       {FaultMode::kGarbage,
        "garbage",
        "",
        "a uniform noise image in place of each frame (detected like any frame)",
        {}},
       Delayed(""),
       Slow(""),
       Intermittent(""),
       {FaultMode::kDistractor,
        "distractor",
        "",
        "a second payload (same sphere, same material) in the rendered scene at `position`, "
        "moving at `velocity`, drawn in a frame with probability `visible_rate` (a flickering "
        "red object): clutter the detector sees in real pixels (the analytic camera has none)",
        {Vector("position", "m", "where it is at the fault's start (world frame)", -10.0, 10.0,
                std::nullopt, &Fault::distractor_W_m),
         Vector("velocity", "m/s", "its constant velocity (world frame)", -10.0, 10.0, 0.0,
                &Fault::distractor_velocity_W_mps),
         Number("visible_rate", "1",
                "probability that it is drawn in a frame (each frame a draw from the fault's "
                "seeded stream; 1: in every frame)",
                0.0, 1.0, 1.0, &Fault::distractor_visible_fraction),
         Vector("sign_size", "m",
                "draws it as a level box (a red sign) of these full sizes x, y, z (world frame) "
                "in the payload's material; any 0: the payload's sphere",
                0.0, 2.0, 0.0, &Fault::distractor_sign_size_m)}}}};
}

std::vector<FaultComponentDecl> BuildComponents() {
  return {VioComponent(),   ImuComponent(),     RateGyroComponent(),
          MotorComponent(), GripperComponent(), CameraComponent()};
}

// The component a sensor message belongs to (none for the gripper's switch).
std::optional<FaultComponent> ComponentOf(const SensorMessage& m) {
  if (std::holds_alternative<ImuSample>(m)) return FaultComponent::kImu;
  if (std::holds_alternative<GyroSample>(m)) return FaultComponent::kRateGyro;
  if (std::holds_alternative<VioSample>(m)) return FaultComponent::kVio;
  if (std::holds_alternative<PayloadDetection>(m) || std::holds_alternative<CameraFrame>(m)) {
    return FaultComponent::kCamera;
  }
  return std::nullopt;
}

// `a` with `b`'s data and `a`'s time stamp (same message type).
void KeepTimeTakeData(const SensorMessage& frozen, SensorMessage* m) {
  const double t_s = Sensor::CaptureTime(*m);
  std::visit(
      [&](auto& now) {
        using T = std::decay_t<decltype(now)>;
        if constexpr (std::is_same_v<T, CameraFrame> || std::is_same_v<T, GripperSample>) {
          return;  // frames are frozen at capture; the switch has no fault
        } else {
          now = std::get<T>(frozen);
          now.time_s = t_s;
        }
      },
      *m);
}

Eigen::Vector3d Gaussian3(std::mt19937_64* rng, double std_dev) {
  std::normal_distribution<double> normal(0.0, std_dev);
  const double x = normal(*rng), y = normal(*rng), z = normal(*rng);
  return {x, y, z};
}

bool InWindow(const Fault& f, double t_s) {
  return t_s >= f.start_s - 1e-9 && t_s < f.end_s - 1e-9;
}

}  // namespace

const std::vector<FaultComponentDecl>& FaultComponents() {
  static const std::vector<FaultComponentDecl> components = BuildComponents();
  return components;
}

Faults::Faults(uint64_t run_seed) : run_seed_(run_seed) {}

void Faults::Clear() { faults_.clear(); }

void Faults::Inject(const Fault& fault) {
  Active a;
  a.fault = fault;
  a.stream_seed = SplitMix64(run_seed_ * 0x9E3779B97F4A7C15ULL + kFaultSalt + faults_.size());
  a.rng.seed(a.stream_seed);
  a.tally.start_s = fault.start_s;
  a.tally.distractor = fault.mode == FaultMode::kDistractor;
  faults_.push_back(std::move(a));
}

bool Faults::Apply(Active* a, double now_s, SensorMessage* m) {
  const Fault& f = a->fault;
  const double t_s = Sensor::CaptureTime(*m);
  // a delayed stream keeps its order: while messages are held, later ones queue behind them
  if (f.mode == FaultMode::kDelayed) {
    const bool in = InWindow(f, t_s);
    if (!in && a->held.empty()) return true;
    a->held.push_back({in ? now_s + f.delay_s : now_s, std::move(*m)});
    return false;
  }
  if (!InWindow(f, t_s)) return true;
  switch (f.mode) {
    case FaultMode::kOff:
      return false;
    case FaultMode::kIntermittent:
      return std::uniform_real_distribution<double>(0.0, 1.0)(a->rng) >= f.drop_fraction;
    case FaultMode::kSlow:
      if (t_s < a->last_kept_s + 1.0 / f.rate_hz - 5e-4) return false;
      a->last_kept_s = t_s;
      return true;
    case FaultMode::kStuck:
      if (f.component == FaultComponent::kCamera) return true;  // frozen at capture
      if (!a->frozen) {
        a->frozen = *m;
      } else {
        KeepTimeTakeData(*a->frozen, m);
      }
      return true;
    case FaultMode::kWrong:
      if (auto* vio = std::get_if<VioSample>(m)) vio->p_WB_W += f.offset_W_m;
      return true;
    case FaultMode::kBias:
      if (auto* imu = std::get_if<ImuSample>(m)) {
        imu->gyro_B_radps += f.gyro_bias_B_radps;
        imu->accel_B_mps2 += f.accel_bias_B_mps2;
      }
      if (auto* gyro = std::get_if<GyroSample>(m)) gyro->gyro_B_radps += f.gyro_bias_B_radps;
      return true;
    case FaultMode::kNoise:
      if (auto* imu = std::get_if<ImuSample>(m)) {
        imu->gyro_B_radps += Gaussian3(&a->rng, f.gyro_noise_radps);
        imu->accel_B_mps2 += Gaussian3(&a->rng, f.accel_noise_mps2);
      }
      if (auto* gyro = std::get_if<GyroSample>(m)) {
        gyro->gyro_B_radps += Gaussian3(&a->rng, f.gyro_noise_radps);
      }
      return true;
    default:
      return true;
  }
}

void Faults::FilterDelivered(double now_s, std::vector<SensorMessage>* messages) {
  incoming_.clear();
  std::swap(incoming_, *messages);
  for (SensorMessage& m : incoming_) {
    const std::optional<FaultComponent> component = ComponentOf(m);
    bool keep = true;
    for (Active& a : faults_) {
      if (!component || a.fault.component != *component) continue;
      keep = Apply(&a, now_s, &m);
      if (!keep) break;
    }
    if (keep) messages->push_back(std::move(m));
  }
  for (Active& a : faults_) {
    while (!a.held.empty() && a.held.front().release_s <= now_s + 1e-9) {
      messages->push_back(std::move(a.held.front().message));
      a.held.pop_front();
    }
  }
}

void Faults::TakeHeld(std::vector<SensorMessage>* out) {
  for (Active& a : faults_) {
    for (Held& h : a.held) out->push_back(std::move(h.message));
    a.held.clear();
  }
}

CameraPixelFault Faults::OnCameraPixels(double now_s) {
  CameraPixelFault pixels;
  for (Active& a : faults_) {
    const Fault& f = a.fault;
    if (f.component != FaultComponent::kCamera || !InWindow(f, now_s)) continue;
    if (f.mode == FaultMode::kStuck) {
      pixels.frozen_whole = &a.frozen_whole;
    } else if (f.mode == FaultMode::kGarbage) {
      pixels.garbage = true;
      pixels.noise_seed = a.rng();
    }
  }
  return pixels;
}

void Faults::OnCameraReading(double now_s, const SystemState& truth, const Params& world_params,
                             bool from_pixels, std::optional<PayloadDetection>* detection) {
  for (Active& a : faults_) {
    const Fault& f = a.fault;
    if (f.component != FaultComponent::kCamera || !InWindow(f, now_s)) continue;
    if (f.mode == FaultMode::kDistractor) {
      TallyDistractorFrame(&a, now_s, truth, world_params, *detection);
      continue;
    }
    if (from_pixels || !*detection) continue;
    PayloadDetection& d = **detection;
    const double t_s = d.time_s;
    if (f.mode == FaultMode::kStuck) {
      // the first detection of the fault again
      if (!a.frozen) {
        a.frozen = SensorMessage(d);
      } else {
        d = std::get<PayloadDetection>(*a.frozen);
        d.time_s = t_s;
      }
    } else if (f.mode == FaultMode::kGarbage) {
      // the analytic camera has no pixels: nothing found in noise
      d = PayloadDetection{};
      d.time_s = t_s;
      d.reason = "camera fault: garbage";
    }
  }
}

bool Faults::MotorThrustFactors(double now_s, Eigen::Vector4d* factor) const {
  bool any = false;
  for (const Active& a : faults_) {
    const Fault& f = a.fault;
    if (f.component != FaultComponent::kMotor) continue;
    if (!any) factor->setOnes();
    any = true;
    if (!InWindow(f, now_s)) continue;
    const int i = static_cast<int>(f.motor);
    (*factor)(i) *= f.mode == FaultMode::kOff ? 0.0 : 1.0 - f.loss;
  }
  return any;
}

bool Faults::DefersRelease(double now_s) {
  bool defer = false;
  for (Active& a : faults_) {
    const Fault& f = a.fault;
    if (f.component != FaultComponent::kGripper || f.mode != FaultMode::kLate) continue;
    if (!InWindow(f, now_s)) continue;
    a.release_pending = true;
    defer = true;
  }
  return defer;
}

bool Faults::TakeGripperRelease(double now_s) {
  bool release = false;
  for (Active& a : faults_) {
    const Fault& f = a.fault;
    if (f.component != FaultComponent::kGripper || a.released) continue;
    const bool early = f.mode == FaultMode::kEarly && now_s >= f.start_s - 1e-9;
    const bool late_due =
        f.mode == FaultMode::kLate && a.release_pending && now_s >= f.end_s - 1e-9;
    if (early || late_due) {
      a.released = true;
      release = true;
    }
  }
  return release;
}

Eigen::Vector3d Faults::DistractorPosition_W(const Fault& f, double now_s) {
  return f.distractor_W_m + f.distractor_velocity_W_mps * (now_s - f.start_s);
}

bool Faults::DistractorDrawn(const Active& a, double now_s) {
  const double p = a.fault.distractor_visible_fraction;
  if (p >= 1.0) return true;
  if (p <= 0.0) return false;
  // one uniform draw per instant (microseconds), from the fault's own stream's seed: a region and
  // the whole frame of one capture, and the chase camera at that instant, see the same
  const uint64_t key = static_cast<uint64_t>(std::llround(now_s * 1e6));
  const double u =
      static_cast<double>(SplitMix64(a.stream_seed ^ SplitMix64(key)) >> 11) * 0x1.0p-53;
  return u < p;
}

void Faults::TallyDistractorFrame(Active* a, double now_s, const SystemState& truth,
                                  const Params& world_params,
                                  const std::optional<PayloadDetection>& detection) {
  FaultFrameTally& t = a->tally;
  ++t.frames;
  const bool drawn = DistractorDrawn(*a, now_s);
  // the distractor's centre in the camera frame: the payload's transform at its position
  SystemState at_distractor = truth;
  at_distractor.p_WL_W = DistractorPosition_W(a->fault, now_s);
  const Eigen::Vector3d p_CD_C = PayloadInCamera_C(world_params, at_distractor);
  t.drawn_frames += drawn ? 1 : 0;
  t.in_image_frames += drawn && InsideImage(world_params, p_CD_C) ? 1 : 0;
  if (!detection || !detection->found) return;
  ++t.detections;
  // on the distractor: the detection's bearing closer to the distractor's than to the payload's
  const Eigen::Vector3d p_CL_C = PayloadInCamera_C(world_params, truth);
  const Eigen::Vector3d b_C = detection->p_CL_C.normalized();
  const double to_payload_rad = std::acos(std::clamp(b_C.dot(p_CL_C.normalized()), -1.0, 1.0));
  const double to_distractor_rad = std::acos(std::clamp(b_C.dot(p_CD_C.normalized()), -1.0, 1.0));
  if (drawn && to_distractor_rad < to_payload_rad) ++t.detections_on_distractor;
}

std::vector<DistractorDraw> Faults::DistractorsDrawn(double now_s) const {
  std::vector<DistractorDraw> out;
  for (const Active& a : faults_) {
    const Fault& f = a.fault;
    if (f.mode != FaultMode::kDistractor || !InWindow(f, now_s)) continue;
    if (!DistractorDrawn(a, now_s)) continue;
    const Eigen::Vector3d p_W = DistractorPosition_W(f, now_s);
    const Eigen::Vector3d& size_m = f.distractor_sign_size_m;
    out.push_back({{p_W.x(), p_W.y(), p_W.z()}, {size_m.x(), size_m.y(), size_m.z()}});
  }
  return out;
}

std::vector<FaultFrameTally> Faults::FrameTallies() const {
  std::vector<FaultFrameTally> out;
  for (const Active& a : faults_) out.push_back(a.tally);
  return out;
}

}  // namespace hpa::sim
