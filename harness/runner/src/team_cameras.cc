// TeamPayloadCameras: the single vehicle's payload camera on every vehicle of a team.

#include "harness/runner/src/team_cameras.h"

#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

#include "hpa/models/camera_model.h"
#include "hpa/models/detection_noise.h"
#include "hpa/models/seed_streams.h"
#include "hpa/models/state.h"
#include "hpa/sim/world.h"

namespace hpa::runner {
namespace {

using Clock = std::chrono::steady_clock;

// Wall time from t0 to now (ms).
double MsSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// The measured detector noise scaled by `scale` (the analytic camera's, as the single vehicle's).
CameraNoiseModel ScaledNoise(double scale) {
  CameraNoiseModel noise = MeasuredDetectorNoise();
  noise.centre_std_px *= scale;
  noise.semi_major_std_px *= scale;
  return noise;
}

}  // namespace

struct TeamPayloadCameras::VehicleCamera {
  VehicleCamera(const Params& params, const sim::WorldProfile& profile,
                const TeamCameraConfig& config, int vehicle)
      : detector(params),
        analytic(params, ScaledNoise(config.detector_noise_scale)),
        analytic_rng(DeriveVehicleSeed(config.seed, SeedStream::kAnalyticCamera, vehicle)),
        in_flight(config.rate.latency_s) {
    if (config.kind == sim::CameraKind::kRendered) {
      image_model = std::make_unique<sim::CameraImageModel>(
          params, profile.camera,
          DeriveVehicleSeed(config.seed, SeedStream::kCameraImage, vehicle));
    }
  }

  std::unique_ptr<sim::CameraImageModel> image_model;  // rendered only
  PayloadDetector detector;                            // on the model's images
  sim::AnalyticCamera analytic;                        // analytic only
  std::mt19937_64 analytic_rng;                        // its noise
  DelayLine<PayloadDetection> in_flight;               // capture to delivery
  cv::Mat image;                                       // the last sensor image
};

Eigen::Vector3d TeamPayloadInCamera_C(const CooperativeTeam& team, const Eigen::VectorXd& x,
                                      int vehicle) {
  using I = CooperativeStateIndex;
  const int v = I::Vehicle(vehicle);
  SystemState s;
  s.p_WL_W = x.segment<3>(I::kPayloadPos);
  s.p_WQ_W = x.segment<3>(v + I::kVehiclePos);
  s.q_WB = Eigen::Quaterniond(x(v + I::kVehicleQuat), x(v + I::kVehicleQuat + 1),
                              x(v + I::kVehicleQuat + 2), x(v + I::kVehicleQuat + 3))
               .normalized();
  return PayloadInCamera_C(team.vehicles.at(static_cast<size_t>(vehicle)).params, s);
}

TeamPayloadCameras::TeamPayloadCameras(const CooperativeTeam& team,
                                       const sim::WorldProfile& profile,
                                       const TeamCameraConfig& config)
    : team_(team), profile_(profile.camera), config_(config) {
  if (!(config.rate.rate_hz > 0.0) || !std::isfinite(config.rate.rate_hz)) {
    throw std::invalid_argument("team payload cameras: rate " +
                                std::to_string(config.rate.rate_hz) + " Hz is not positive");
  }
  if (!(config.rate.latency_s >= 0.0) || !std::isfinite(config.rate.latency_s)) {
    throw std::invalid_argument("team payload cameras: latency " +
                                std::to_string(config.rate.latency_s) + " s is negative");
  }
  const int n = static_cast<int>(team.vehicles.size());
  for (int i = 0; i < n; ++i) {
    vehicles_.push_back(std::make_unique<VehicleCamera>(
        team.vehicles[static_cast<size_t>(i)].params, profile, config, i));
  }
  counts_.resize(static_cast<size_t>(n));
}

TeamPayloadCameras::~TeamPayloadCameras() = default;

void TeamPayloadCameras::Capture(sim::TeamWorld& world, double t_s) {
  world.GetTruth(&truth_);
  for (size_t i = 0; i < vehicles_.size(); ++i) {
    const int vehicle = static_cast<int>(i);
    const Params& params = team_.vehicles[i].params;
    const Eigen::Vector3d p_CL_C = TeamPayloadInCamera_C(team_, truth_.x, vehicle);
    VehicleCameraCounts& counts = counts_[i];
    ++counts.frames;
    counts.payload_in_view_frames += InsideImage(params, p_CL_C) ? 1 : 0;
    if (config_.kind == sim::CameraKind::kNone) continue;
    PayloadDetection detection = Detect(world, vehicle, p_CL_C, t_s);
    counts.found_frames += detection.found ? 1 : 0;
    vehicles_[i]->in_flight.Push(t_s, std::move(detection));
  }
}

PayloadDetection TeamPayloadCameras::Detect(sim::TeamWorld& world, int i,
                                            const Eigen::Vector3d& p_CL_C, double t_s) {
  VehicleCamera& camera = *vehicles_[static_cast<size_t>(i)];
  if (config_.kind == sim::CameraKind::kAnalytic) {
    return camera.analytic.Measure(p_CL_C, t_s, camera.analytic_rng);
  }
  // the pinhole render the model expects, the sensor's image, the detector on its pixels; no
  // motion blur (the single vehicle's image motion reads its own world), noise keyed by the step
  const Params& params = team_.vehicles[static_cast<size_t>(i)].params;
  VehicleCameraCounts& counts = counts_[static_cast<size_t>(i)];
  world.renderer().RenderOnboardCamera(i, params.camera_width_px, params.camera_height_px,
                                       camera.image_model->render_fovy_deg(), profile_.draw_cable,
                                       &pinhole_);
  counts.render_ms.push_back(world.renderer().last_render_ms());
  const auto t0 = Clock::now();
  const uint64_t frame = static_cast<uint64_t>(std::llround(t_s / sim::World::kPhysicsDt_s));
  camera.image_model->ApplyOptics(pinhole_, frame, &camera.image);
  counts.image_model_ms.push_back(MsSince(t0));
  const auto t1 = Clock::now();
  PayloadDetection detection = camera.detector.Detect(camera.image, t_s);
  counts.detector_ms.push_back(MsSince(t1));
  return detection;
}

void TeamPayloadCameras::TakeDelivered(int vehicle, double t_s,
                                       std::vector<PayloadDetection>* out) {
  if (vehicle < 0 || vehicle >= static_cast<int>(vehicles_.size())) {
    throw std::out_of_range("team payload cameras: no vehicle " + std::to_string(vehicle));
  }
  out->clear();
  DelayLine<PayloadDetection>& line = vehicles_[static_cast<size_t>(vehicle)]->in_flight;
  while (std::optional<PayloadDetection> d = line.PopReady(t_s)) out->push_back(std::move(*d));
}

const cv::Mat& TeamPayloadCameras::last_image(int vehicle) const {
  if (vehicle < 0 || vehicle >= static_cast<int>(vehicles_.size())) {
    throw std::out_of_range("team payload cameras: no vehicle " + std::to_string(vehicle));
  }
  return vehicles_[static_cast<size_t>(vehicle)]->image;
}

}  // namespace hpa::runner
