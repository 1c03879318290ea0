// The payload camera component: its clock, the analytic model and the rendered read-out.

#include "hpa/sim/payload_camera.h"

#include <chrono>
#include <cmath>

#include "hpa/models/camera_model.h"
#include "hpa/models/seed_streams.h"
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

double MsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

// Adds the world's timing of the frame it rendered last to the capture's.
void AddRenderTiming(World& world, CameraCapture* capture) {
  capture->render_ms += world.renderer().last_camera_timing().render_ms;
  capture->image_model_ms += world.renderer().last_camera_timing().image_model_ms;
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

std::optional<CameraCapture> PayloadCameraSensor::Capture(
    World& world, int64_t step, double time_s, CameraReadout* readout,
    std::optional<PayloadDetection>* detection, std::optional<CameraFrame>* frames) {
  // the k-th frame is due at the step nearest k / rate (a step with no capture call skips it)
  const auto step_of = [&](int64_t k) {
    return static_cast<int64_t>(std::llround(k * physics_hz_ / rate_hz_));
  };
  while (step_of(next_frame_) < step) ++next_frame_;
  if (step_of(next_frame_) != step) return std::nullopt;
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
    case CameraKind::kRendered:
      if (readout->SendsFrames()) {
        *frames = RenderFrames(world, time_s, readout, &capture);
      } else {
        *detection = RenderAndDetect(world, time_s, readout, &capture);
        capture.detected = (*detection)->found;
      }
      break;
  }
  return capture;
}

// The readout's region rendered, the whole frame only when its detector asks for it (when the
// region cannot decide, or there is none).
PayloadDetection PayloadCameraSensor::RenderAndDetect(World& world, double time_s,
                                                      CameraReadout* readout,
                                                      CameraCapture* capture) {
  CameraFrame frame;
  frame.capture_time_s = time_s;
  frame.region = readout->Region();
  if (frame.region.area() > 0) {
    world.renderer().RenderPayloadCamera(&rendered_, frame.region);
    AddRenderTiming(world, capture);
    frame.region_bgr = rendered_;
  }
  // the whole frame into the same buffer (the region has been read by then); its render time
  // is not the detector's
  double whole_read_ms = 0.0;
  bool whole_read = false;
  const WholeFrameReader read_whole = [&]() -> const cv::Mat& {
    const auto render_start = std::chrono::steady_clock::now();
    world.renderer().RenderPayloadCamera(&rendered_, cv::Rect());
    AddRenderTiming(world, capture);
    whole_read = true;
    whole_read_ms = MsSince(render_start);
    return rendered_;
  };
  const auto detect_start = std::chrono::steady_clock::now();
  PayloadDetection detection = readout->Detect(frame, read_whole);
  capture->detector_ms += MsSince(detect_start) - whole_read_ms;
  capture->region_only = !whole_read;
  capture->frame = &rendered_;
  return detection;
}

// The region of interest the stack asked for last and the whole frame (its fallback), each into
// a buffer of the readout's (its shared ring); the pixels are those the in-process path renders.
CameraFrame PayloadCameraSensor::RenderFrames(World& world, double time_s, CameraReadout* readout,
                                              CameraCapture* capture) {
  CameraFrame out;
  out.capture_time_s = time_s;
  const cv::Rect region = readout->Region();
  if (region.area() > 0) {
    cv::Mat* bgr = readout->NextFrameSlot(&out.region_slot);
    world.renderer().RenderPayloadCamera(bgr, region);
    AddRenderTiming(world, capture);
    out.region = region;
    out.region_bgr = *bgr;
  }
  cv::Mat* whole = readout->NextFrameSlot(&out.whole_slot);
  world.renderer().RenderPayloadCamera(whole, cv::Rect());
  AddRenderTiming(world, capture);
  out.whole_bgr = *whole;
  capture->frame = whole;
  return out;
}

}  // namespace hpa::sim
