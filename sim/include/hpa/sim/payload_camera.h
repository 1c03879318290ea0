#pragma once
// The payload camera as a component of the world: it declares its rate, latency and noise (its
// row of the rate table), fires on its own clock at the start of a tick (the state the flight
// stack's tick sees) and produces one message the world delivers through its delay line: a
// detection (the analytic camera's, or the flight stack's detector run on the rendered pixels at
// capture), or the rendered frames for a flight stack that detects on its side. Who detects is
// the caller's CameraReadout: the component never links the detector (flight code).

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

class World;
struct WorldConfig;

/// What the payload camera produces.
enum class CameraKind {
  kNone,      // no image reaches the flight code (ground truth): the capture is recorded only
  kAnalytic,  // the detection the detector would return, from the true payload plus its noise
  kRendered,  // rendered pixels, detected by the caller's readout (or sent to the flight stack)
};

/// The payload camera's part of a WorldConfig.
struct PayloadCameraConfig {
  CameraKind kind = CameraKind::kNone;
  double detector_noise_scale = 1.0;  // the analytic camera's noise, times the measured one
};

/// How the flight stack reads rendered frames out (the runner implements it): the region it
/// wants first, who detects in the pixels, or where frames sent to it go.
class CameraReadout {
 public:
  virtual ~CameraReadout() = default;
  /// The region of the frame to read first (empty: only the whole frame).
  virtual cv::Rect Region() = 0;
  /// True: the frames travel to the flight stack, which detects on its side (Detect is not
  /// called; the region, if any, and the whole frame are read out into NextFrameSlot buffers).
  virtual bool SendsFrames() const { return false; }
  /// Detects in `frame` (its region read out, if it has one), reading the whole frame of the same
  /// exposure with `read_whole` only when it needs it.
  virtual PayloadDetection Detect(const CameraFrame& frame, const WholeFrameReader& read_whole) = 0;
  /// The buffer the next frame sent to the flight stack is rendered into, and its slot.
  virtual cv::Mat* NextFrameSlot(int* slot) = 0;
};

/// One capture, as the recorders see it (metrics inputs, the video's HUD).
struct CameraCapture {
  double time_s = 0.0;             // capture time
  bool payload_in_image = false;   // the true payload inside the image
  bool detected = false;           // detected at capture (analytic, or the readout's detector)
  const cv::Mat* frame = nullptr;  // the rendered whole frame or region (nullptr: none)
  double render_ms = 0.0, image_model_ms = 0.0, detector_ms = 0.0;  // rendered frames only
  bool region_only = false;  // rendered and detected in the readout's region alone
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
  /// At step `step` of `world` (its time `time_s`): nothing unless a frame is due; else the
  /// capture of the true payload, with what to deliver in *detection or *frames (neither for
  /// kNone).
  std::optional<CameraCapture> Capture(World& world, int64_t step, double time_s,
                                       CameraReadout* readout,
                                       std::optional<PayloadDetection>* detection,
                                       std::optional<CameraFrame>* frames);

 private:
  PayloadDetection RenderAndDetect(World& world, double time_s, CameraReadout* readout,
                                   CameraCapture* capture);
  CameraFrame RenderFrames(World& world, double time_s, CameraReadout* readout,
                           CameraCapture* capture);

  Params params_;  // flight params: the camera's mount and intrinsics as the detector knows them
  PayloadCameraConfig config_;
  double physics_hz_, rate_hz_;
  uint64_t seed_;
  std::mt19937_64 rng_;  // the analytic camera's noise
  AnalyticCamera analytic_;
  int64_t next_frame_ = 0;  // index k of the next frame (due at the step nearest k / rate)
  cv::Mat rendered_;        // the in-process frame buffer, reused frame to frame
  SensorDeclaration declaration_;
};

}  // namespace hpa::sim
