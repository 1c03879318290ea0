#pragma once
// The lockstep loop of one team run (private to the runner), in the shape of the single
// vehicle's RunLoop: the team's world, each vehicle's flight code (through one TeamFlightLink)
// and autopilot, and the per-tick steps, each a method of its own. Each vehicle's flight code
// sees its own state and the payload's as motion capture delivered them (or the truth, with the
// scenario's ground-truth switch), never another vehicle's.

#include <Eigen/Core>
#include <chrono>
#include <memory>
#include <optional>
#include <vector>

#include "hpa/autopilot/autopilot.h"
#include "hpa/estimator/vehicle_filter.h"
#include "hpa/models/lockstep.h"
#include "hpa/scenarios/runner.h"
#include "hpa/sim/team_world.h"
#include "harness/runner/src/team_cameras.h"
#include "harness/runner/src/team_flight_link.h"

namespace hpa::runner {

/// One team run's world, flight code and schedule; Run() steps it tick by tick.
class TeamRunLoop {
 public:
  /// The team's world (reset to its start) flown by `flight` on the scenario's schedule; rows and
  /// metrics go into *result, which must outlive the loop.
  TeamRunLoop(const Scenario& scenario, const Params& params, const RunOptions& options,
              std::unique_ptr<sim::TeamWorld> world, std::shared_ptr<const Reference> reference,
              std::unique_ptr<TeamFlightLink> flight, RunResult* result);

  /// Runs to the end, a crash or a stop request, then tells the flight code the run is over; an
  /// error on the way ends the run with a run error naming it and its time (the results so far
  /// are kept).
  void Run();

  /// The crash, the time reached, the vehicles' separation and the last step's extremes, into
  /// the metrics (after Run).
  void Finish();

  /// Each vehicle's rate-loop allocations  (N)
  const std::vector<int>& rate_steps() const { return rate_steps_; }
  /// Each vehicle's allocations that fell short of its command  (N)
  const std::vector<int>& saturated_steps() const { return saturated_; }
  /// Whether each vehicle flies on its onboard estimate of its own state (its VehicleFilter on
  /// its own IMU and VIO) rather than on motion capture or the truth.
  bool onboard() const { return !filters_.empty(); }
  /// Each vehicle's payload camera (null: the scenario flies none).
  const TeamPayloadCameras* cameras() const { return cameras_.get(); }

 private:
  using Clock = std::chrono::steady_clock;

  bool Tick();  // one physics tick; false: the run ends here
  void ApplyDueEvents(double t);
  void ReadBodies(double t);  // this tick's truth, extremes and readings
  void ControlStep(double t);
  void RateLoopStep();
  void OnboardStep();  // each vehicle's delivered IMU, VIO and rate-gyro samples to its filter
  void DelayOwnStates(double t);   // each vehicle's own state into and out of its latency
  void DeliverCommands(double t);  // the commands whose latency has passed to the rate loops
  void CameraStep(double t);       // each vehicle's camera frame, its detections taken
  // vehicle i's own state for its view: its filter's estimate, else its reading of itself
  bool OwnState(int i, double t, TeamView* view) const;
  void FlyRateLoop(int i, const Eigen::Vector3d& w_B_radps);  // one autopilot update
  void VideoStep();
  bool StepWorld();  // false: crashed
  void ShowProgress(double t);

  const Scenario& scenario_;
  const RunOptions& options_;
  RunResult* result_;
  Metrics& metrics_;  // result_->metrics
  Clock::time_point wall_start_;
  int n_ = 0;  // vehicles

  std::unique_ptr<sim::TeamWorld> world_;
  std::shared_ptr<const Reference> reference_;          // for the log
  std::unique_ptr<TeamFlightLink> flight_;              // each vehicle's controller
  std::vector<std::unique_ptr<Autopilot>> autopilots_;  // each vehicle's rate loop  (N)

  // schedule
  long tick_ = 0, end_tick_ = 0;
  LockstepClock clock_;
  int control_loop_ = -1, rate_loop_ = -1, video_loop_ = -1, camera_loop_ = -1;
  size_t next_event_ = 0;

  // what each vehicle's flight code holds: the latest reading of each body (payload first)
  std::vector<std::optional<sim::BodyReading>> latest_;  // (N + 1)
  std::vector<std::optional<BodyRateCommand>> command_;  // each vehicle's last  (N)
  std::vector<TeamLogRow::Vehicle> last_;                // each vehicle's log columns  (N)
  std::vector<int> rate_steps_, saturated_;              // (N each)
  double min_separation_m_ = 0.0;
  // the profile's latencies (empty when it has none): each vehicle's commands on their way to
  // its rate loop (compute + transport), its own state on its way to its flight code (estimate)
  // and the newest that has arrived  (N each)
  std::vector<DelayLine<BodyRateCommand>> commands_in_flight_;
  std::vector<DelayLine<TeamView>> own_in_flight_;
  std::vector<std::optional<TeamView>> own_arrived_;
  // each vehicle's payload camera, and the detections delivered to a vehicle at a tick
  std::unique_ptr<TeamPayloadCameras> cameras_;
  std::vector<PayloadDetection> detections_;
  // onboard estimation: each vehicle's filter and its newest rate-gyro sample  (N each)
  std::vector<VehicleFilter> filters_;
  std::vector<std::optional<GyroSample>> rate_gyro_;
  // refilled every physics step, their memory kept
  sim::TeamTruth truth_;
  std::vector<sim::BodyReading> delivered_;
  std::vector<sim::SensorMessage> sensor_messages_;
  bool show_progress_ = false;
  int last_progress_pct_ = -1;
};

/// A vehicle's and the payload's extremes at the physics rate (UpdateVehicleExtremes per
/// vehicle, and the payload's tilt).
void UpdateTeamExtremes(const sim::TeamTruth& truth, Metrics* metrics);

}  // namespace hpa::runner
