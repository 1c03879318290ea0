#pragma once
// Each team vehicle's payload camera (private to the runner; docs/cooperative.md, "Payload
// cameras"): the single vehicle's camera on every vehicle of a team. Rendered, each frame is the
// vehicle's pinhole render (TeamRenderer) turned into the sensor's image by the single vehicle's
// camera image model (CameraImageModel, the world profile's camera part) and searched by its
// detector (PayloadDetector); analytic, the single vehicle's analytic camera (AnalyticCamera) on
// the payload's centre seen from the vehicle. Either way each detection reaches its vehicle after
// the camera's latency. Observing never changes the world: the cameras only read it.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "hpa/estimator/payload_detector.h"
#include "hpa/models/cooperative_model.h"
#include "hpa/models/lockstep.h"
#include "hpa/models/sensor_types.h"
#include "hpa/sim/analytic_camera.h"
#include "hpa/sim/camera_image_model.h"
#include "hpa/sim/payload_camera.h"
#include "hpa/sim/team_world.h"
#include "hpa/sim/world_profile.h"

namespace hpa::runner {

/// What a team's payload cameras are made from (besides the team and the world profile).
struct TeamCameraConfig {
  sim::CameraKind kind = sim::CameraKind::kRendered;  // rendered, analytic, or none (truth only)
  StreamRate rate{30.0, 0.03};  // frame rate and capture-to-delivery latency (RateTable::camera)
  uint64_t seed = 1;            // the run's seed: each vehicle's streams are derived from it
  double detector_noise_scale = 1.0;  // the analytic camera's noise, times the measured one
};

/// One vehicle's payload-camera record over a run (its metrics' inputs).
struct VehicleCameraCounts {
  int frames = 0;                      // captures
  int payload_in_view_frames = 0;      // captures with the true payload centre inside the image
  int found_frames = 0;                // captures whose detection found the payload
  std::vector<double> render_ms;       // each rendered capture's render wall time (ms)
  std::vector<double> image_model_ms;  // each rendered capture's image model wall time (ms)
  std::vector<double> detector_ms;     // each rendered capture's detector wall time (ms)
};

/// The payload's centre in vehicle `vehicle`'s camera frame C (OpenCV axes, m) for the team's
/// state x (CooperativeStateIndex layout): PayloadInCamera_C with the vehicle as the quadrotor.
Eigen::Vector3d TeamPayloadInCamera_C(const CooperativeTeam& team, const Eigen::VectorXd& x,
                                      int vehicle);

/// Every vehicle's payload camera in one team run: capture at the camera's rate, take each
/// vehicle's detections once their latency has passed.
class TeamPayloadCameras {
 public:
  /// The cameras of `team`'s vehicles (each its own Params' mount, intrinsics and lens) with
  /// `profile`'s camera part; each vehicle's image noise and analytic noise seeded apart
  /// (DeriveVehicleSeed of config.seed and the vehicle). Throws std::invalid_argument for a
  /// non-positive rate or a negative latency.
  TeamPayloadCameras(const CooperativeTeam& team, const sim::WorldProfile& profile,
                     const TeamCameraConfig& config);
  ~TeamPayloadCameras();
  TeamPayloadCameras(const TeamPayloadCameras&) = delete;
  TeamPayloadCameras& operator=(const TeamPayloadCameras&) = delete;

  /// The cameras' rate and latency, for the caller's schedule (a LockstepClock loop).
  const StreamRate& rate() const { return config_.rate; }
  /// Every vehicle's frame of `world` now (its time t_s): whether the true payload centre is in
  /// its image, and its detection (rendered, modelled and detected; or analytic), queued for
  /// delivery at t_s + latency. Reads the world only (its renderer draws a render-only copy).
  void Capture(sim::TeamWorld& world, double t_s);
  /// Vehicle's detections whose latency has passed at t_s, in capture order, into `out`
  /// (cleared first, its memory kept). A vehicle outside 0 .. N-1 throws std::out_of_range.
  void TakeDelivered(int vehicle, double t_s, std::vector<PayloadDetection>* out);
  /// Each vehicle's record so far  (N)
  const std::vector<VehicleCameraCounts>& counts() const { return counts_; }
  /// Vehicle's last sensor image (CV_8UC3, the sensor's size; empty before a rendered capture).
  const cv::Mat& last_image(int vehicle) const;

 private:
  struct VehicleCamera;  // one vehicle's image model, detector, analytic camera and delay line
  // vehicle i's detection of this capture (p_CL_C: the true payload centre in its camera)
  PayloadDetection Detect(sim::TeamWorld& world, int i, const Eigen::Vector3d& p_CL_C, double t_s);

  CooperativeTeam team_;
  sim::CameraImageProfile profile_;
  TeamCameraConfig config_;
  std::vector<std::unique_ptr<VehicleCamera>> vehicles_;  // (N)
  std::vector<VehicleCameraCounts> counts_;               // (N)
  sim::TeamTruth truth_;                                  // refilled at each capture
  cv::Mat pinhole_;                                       // the render, reused
};

}  // namespace hpa::runner
