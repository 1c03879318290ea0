// The payload camera component: its clock, the analytic model and the rendered read-out.

#include "hpa/sim/payload_camera.h"

#include <cmath>

#include "hpa/models/camera_model.h"
#include "hpa/models/seed_streams.h"
#include "hpa/sim/faults.h"
#include "hpa/sim/world.h"

namespace hpa::sim {
namespace {

// The measured detector noise scaled by the scenario's factor.
CameraNoiseModel ScaledNoise(double scale) {
  CameraNoiseModel noise = MeasuredDetectorNoise();
  noise.centre_std_px *= scale;
  noise.semi_major_std_px *= scale;
  return noise;
}

// Adds the world's timing of the frame it rendered last to *render_ms and *image_model_ms.
void AddRenderTiming(World& world, double* render_ms, double* image_model_ms) {
  *render_ms += world.renderer().last_camera_timing().render_ms;
  *image_model_ms += world.renderer().last_camera_timing().image_model_ms;
}

}  // namespace

PayloadCameraSensor::PayloadCameraSensor(const WorldConfig& config)
    : params_(config.params),
      config_(config.camera),
      physics_hz_(config.rates.physics_hz),
      rate_hz_(config.rates.camera.rate_hz),
      seed_(DeriveSeed(config.seed, SeedStream::kAnalyticCamera)),
      rng_(seed_),
      analytic_(config.params, ScaledNoise(config.camera.detector_noise_scale)) {
  declaration_ = {"payload camera", config.rates.camera.rate_hz, config.rates.camera.latency_s,
                  "rendered: the camera image model; analytic: the detector's measured noise",
                  "RateTable::camera, estimation.camera_latency"};
}

void PayloadCameraSensor::Reset() {
  rng_.seed(seed_);
  next_frame_ = 0;
}

// The k-th frame is due at the step nearest k / rate.
int64_t PayloadCameraSensor::StepOfFrame(int64_t k) const {
  return static_cast<int64_t>(std::llround(k * physics_hz_ / rate_hz_));
}

bool PayloadCameraSensor::FrameDue(int64_t step) const {
  int64_t k = next_frame_;
  while (StepOfFrame(k) < step) ++k;
  return StepOfFrame(k) == step;
}

std::optional<CameraCapture> PayloadCameraSensor::Capture(
    World& world, int64_t step, double time_s, const cv::Rect& region, Faults* faults,
    std::optional<PayloadDetection>* detection) {
  // a step with no capture call skips its frame
  while (StepOfFrame(next_frame_) < step) ++next_frame_;
  if (StepOfFrame(next_frame_) != step) return std::nullopt;
  ++next_frame_;

  const Eigen::Vector3d p_CL_C = PayloadInCamera_C(params_, world.GetTruth().state);
  CameraCapture capture;
  capture.time_s = time_s;
  capture.payload_in_image = InsideImage(params_, p_CL_C);
  switch (config_.kind) {
    case CameraKind::kNone:
      break;
    case CameraKind::kAnalytic:
      *detection = analytic_.Measure(p_CL_C, time_s, rng_);
      capture.detected = (*detection)->found;
      break;
    case CameraKind::kRendered: {
      const CameraPixelFault fault =
          faults != nullptr ? faults->OnCameraPixels(time_s) : CameraPixelFault{};
      capture.exposure.emplace(&world, &rendered_, time_s, region, fault);
      break;
    }
  }
  return capture;
}

CameraExposure::CameraExposure(World* world, cv::Mat* buffer, double time_s, const cv::Rect& region,
                               const CameraPixelFault& fault)
    : world_(world), buffer_(buffer), fault_(fault) {
  frame_.capture_time_s = time_s;
  // a stuck camera's first frame is the whole frame it repeats
  if (fault_.frozen_whole != nullptr && fault_.frozen_whole->empty()) {
    world_->renderer().RenderPayloadCamera(fault_.frozen_whole, cv::Rect());
    AddRenderTiming(*world_, &render_ms_, &image_model_ms_);
  }
  if (region.area() > 0) {
    Read(region);
    frame_.region = region;
    frame_.region_bgr = *buffer_;
  }
}

const cv::Mat& CameraExposure::ReadWhole() {
  if (!whole_read_) {
    Read(cv::Rect());
    whole_read_ = true;
  }
  return *buffer_;
}

void CameraExposure::Read(const cv::Rect& region) {
  if (fault_.garbage) {
    // one noise image per capture, drawn whole at the first read: its region is the whole
    // image's there, so a later read finds it drawn
    if (!noise_drawn_) {
      buffer_->create(world_->renderer().PayloadCameraSize(), CV_8UC3);
      cv::RNG noise(fault_.noise_seed);
      noise.fill(*buffer_, cv::RNG::UNIFORM, 0, 256);
      noise_drawn_ = true;
    }
    return;
  }
  if (fault_.frozen_whole != nullptr) {
    if (region.area() > 0) {
      buffer_->create(fault_.frozen_whole->size(), CV_8UC3);
      (*fault_.frozen_whole)(region).copyTo((*buffer_)(region));
    } else {
      fault_.frozen_whole->copyTo(*buffer_);
    }
    return;
  }
  world_->renderer().RenderPayloadCamera(buffer_, region);
  AddRenderTiming(*world_, &render_ms_, &image_model_ms_);
}

}  // namespace hpa::sim
