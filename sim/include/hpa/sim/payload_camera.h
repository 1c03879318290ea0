#pragma once
// The payload camera as a component of the world: it declares its rate, latency and noise (its
// row of the rate table) and fires on its own clock at the start of a tick (the state the flight
// stack's tick sees). The analytic camera's detection is its message; a rendered frame is an
// exposure the flight stack reads out (region first, the whole frame if it asks) and detects in
// on its side, handing back what it made of it (World::QueueCameraMessage). The simulator
// renders; it never calls the detector (flight code).

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <random>

#include "hpa/models/camera_frame.h"
#include "hpa/models/params.h"
#include "hpa/models/sensor_types.h"
#include "hpa/sim/analytic_camera.h"
#include "hpa/sim/sensor_declaration.h"

namespace hpa::sim {

class Faults;
class World;
struct WorldConfig;

/// What the payload camera produces.
enum class CameraKind {
  kNone,      // no image reaches the flight code (ground truth): the capture is recorded only
  kAnalytic,  // the detection the detector would return, from the true payload plus its noise
  kRendered,  // rendered pixels, read out by the flight stack (which detects in them)
};

/// The payload camera's part of a WorldConfig.
struct PayloadCameraConfig {
  CameraKind kind = CameraKind::kNone;
  double detector_noise_scale = 1.0;  // the analytic camera's noise, times the measured one
};

/// A pixel fault on the payload camera at one capture (Faults::OnCameraPixels): the frame it
/// repeats (stuck), or the seed of the noise image it gives (garbage).
struct CameraPixelFault {
  cv::Mat* frozen_whole = nullptr;  // stuck: the fault's first whole frame (empty: this is it)
  bool garbage = false;             // uniform noise in every pixel, drawn from noise_seed
  uint64_t noise_seed = 0;
};

/// One rendered exposure of the payload camera, readable until the world steps: the region the
/// flight stack asked for, rendered at capture, and the whole frame when its reader asks (the
/// world renders; the flight stack detects). Pixel faults are already in what it reads.
class CameraExposure {
 public:
  /// The exposure captured at `time_s` in `world` (not owned), rendered into `buffer` (not
  /// owned), with `region` read at capture and the pixel fault `fault`.
  CameraExposure(World* world, cv::Mat* buffer, double time_s, const cv::Rect& region,
                 const CameraPixelFault& fault);
  /// Its capture time and the region's pixels (frame().region_bgr; no whole frame).
  const CameraFrame& frame() const { return frame_; }
  /// The whole frame of the same exposure (rendered on the first call, into the same buffer:
  /// the region's pixels are gone after it).
  const cv::Mat& ReadWhole();
  /// Whether the whole frame was read.
  bool whole_read() const { return whole_read_; }
  /// What was read last: the whole frame, or the region's buffer.
  const cv::Mat& pixels() const { return *buffer_; }
  /// Wall time of its renders and of their image model so far (ms).
  double render_ms() const { return render_ms_; }
  double image_model_ms() const { return image_model_ms_; }

 private:
  void Read(const cv::Rect& region);  // renders `region` (empty: whole) with the pixel fault

  World* world_;
  cv::Mat* buffer_;
  CameraPixelFault fault_;
  CameraFrame frame_;
  bool whole_read_ = false;
  bool noise_drawn_ = false;  // garbage: the capture's noise image is in the buffer
  double render_ms_ = 0.0, image_model_ms_ = 0.0;
};

/// One capture, as the recorders see it (metrics inputs, the video's HUD).
struct CameraCapture {
  double time_s = 0.0;             // capture time
  bool payload_in_image = false;   // the true payload inside the image
  bool detected = false;           // detected at capture (analytic, or the flight stack's)
  const cv::Mat* frame = nullptr;  // the rendered whole frame or region (nullptr: none)
  double render_ms = 0.0, image_model_ms = 0.0, detector_ms = 0.0;  // rendered frames only
  bool region_only = false;                // rendered and detected in the requested region alone
  std::optional<CameraExposure> exposure;  // kRendered: what the flight stack reads out
};

/// The payload camera: its declaration, its clock, the analytic model and the rendered path.
class PayloadCameraSensor {
 public:
  /// The camera of a world with `config` (its rates, flight params, seed and camera part).
  explicit PayloadCameraSensor(const WorldConfig& config);
  /// Its row of the rate table.
  const SensorDeclaration& declaration() const { return declaration_; }
  /// Back to its state at World::Reset (its generator re-seeded, its clock at the first frame).
  void Reset();
  /// Whether a frame is due at step `step` (Capture would fire there).
  bool FrameDue(int64_t step) const;
  /// At step `step` of `world` (its time `time_s`): nothing unless a frame is due; else the
  /// capture of the true payload: the analytic camera's detection to deliver in *detection, or
  /// the rendered exposure (`region` read at capture, `faults`' pixel faults in it; faults may be
  /// null) for the flight stack to read out.
  std::optional<CameraCapture> Capture(World& world, int64_t step, double time_s,
                                       const cv::Rect& region, Faults* faults,
                                       std::optional<PayloadDetection>* detection);

 private:
  int64_t StepOfFrame(int64_t k) const;  // the step the k-th frame is due at

  Params params_;  // flight params: the camera's mount and intrinsics as the detector knows them
  PayloadCameraConfig config_;
  double physics_hz_, rate_hz_;
  uint64_t seed_;
  std::mt19937_64 rng_;  // the analytic camera's noise
  AnalyticCamera analytic_;
  int64_t next_frame_ = 0;  // index k of the next frame (due at the step nearest k / rate)
  cv::Mat rendered_;        // the exposure's buffer, reused frame to frame
  SensorDeclaration declaration_;
};

}  // namespace hpa::sim
