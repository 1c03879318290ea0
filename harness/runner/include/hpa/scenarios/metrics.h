#pragma once
// Run metrics exactly as docs/design.md section 8 defines them, and the expect check.

#include <optional>
#include <string>
#include <vector>

#include "hpa/controller/controller.h"
#include "hpa/controller/reference.h"
#include "hpa/estimator/estimator_health.h"
#include "hpa/models/state.h"
#include "hpa/scenarios/scenario.h"
#include "hpa/sim/faults.h"

namespace hpa {

/// One row per control step (150 Hz): what log.csv holds.
struct LogRow {
  double time_s = 0.0;
  SystemState truth;         // true state, truth.mode = true cable mode
  SystemState estimate;      // what flight code saw (equals truth with ground_truth)
  ReferencePoint reference;  // payload reference and flat quadrotor reference
  BodyRateCommand command;   // controller output
  ControlStatus status = ControlStatus::kSuccess;
  double solve_time_ms = 0.0;
  double cost = 0.0;
  double cable_tension_N = 0.0;  // true tension (MuJoCo tendon-limit force)
  bool gripper_active = false;
  bool mixer_saturated = false;        // the rate loop's last allocation gave less than demanded
  int estimator_rejected_updates = 0;  // gated-out measurements so far (0 with ground truth)
  int estimator_resets = 0;            // forced accepts after runs of rejections so far
  // the health check's re-initialisations so far, by cause (none: the flight stack did not
  // report them per step)
  std::optional<EstimatorHealthResets> estimator_health_resets;
};

/// One row per control step of a team run: log.csv's columns, the payload's, then each
/// vehicle's (docs/cooperative.md).
struct TeamLogRow {
  /// One vehicle's columns.
  struct Vehicle {
    double cable_length_m = 0.0;        // true |p_A - p_Q|
    double cable_tension_N = 0.0;       // true tension (MuJoCo tendon-limit force)
    CableMode mode = CableMode::kTaut;  // true cable mode
    bool taut_seen = true;              // its controller's reading of its cable
    BodyRateCommand command;            // its controller's output
    ControlStatus status = ControlStatus::kSuccess;
    double solve_time_ms = 0.0;
    bool mixer_saturated = false;  // its rate loop's last allocation fell short
    // its own position as its flight code saw it at this step (onboard: its filter's estimate;
    // else the motion capture's or the truth's reading)  (3)
    Eigen::Vector3d p_WQ_seen_W = Eigen::Vector3d::Zero();
    // its onboard filter's gated-out measurements and restarts plus forced accepts so far (0 on
    // motion capture or the truth)
    int estimator_rejected_updates = 0;
    int estimator_resets = 0;
  };
  double time_s = 0.0;
  Eigen::VectorXd x_true;    // true team state (CooperativeStateIndex layout)
  ReferencePoint reference;  // the payload's reference
  std::vector<Vehicle> vehicles;
};

/// One fault event's window, for its recovery metrics (docs/faults.md).
struct FaultWindow {
  int event = 0;                  // its index in the scenario's events
  std::string component, mode;    // as written in the event
  double start_s = 0.0;           // when it started
  std::optional<double> end_s;    // when it ended (none: it lasted to the end of the run)
  double tracking_bound_m = 0.1;  // payload error counted as tracking again
  int vehicle = 0;                // the vehicle it hit (0: the single vehicle)
};

/// How the flight code recovered from one fault event (metrics.json `faults`); each time is null
/// where it does not apply or never happened.
struct FaultRecovery {
  FaultWindow window;
  // from its start to the first control step whose estimate flags it (a rejected update, a
  // forced accept or the payload lost, beyond the counts at the start)
  std::optional<double> health_flag_s;
  bool payload_lost = false;  // the estimate flagged the payload lost after the start
  // from its end (its start when it never ended) until the payload is back in view (its lost
  // flag clear for good within the span); null when never lost or never back
  std::optional<double> payload_back_in_view_s;
  bool tracking_left_bound = false;  // the payload error exceeded the bound in the span
  // from its end until the payload error is back within the bound for the rest of the span;
  // null when it never left it or never came back
  std::optional<double> tracking_recovered_s;
  std::optional<double> tracking_error_max_m;  // largest payload error in the span
  // largest error of the onboard estimate of the quadrotor's position in the span (null with
  // ground truth)
  std::optional<double> estimate_error_max_m;
  // the filters' forced accepts and gated-out measurements in the span (null: no onboard
  // estimator flew, as for a team on motion capture)
  std::optional<int> estimator_resets = 0;
  std::optional<int> rejected_updates = 0;
  // the health check's re-initialisations in the span, by cause (null: the log has no per-step
  // counts by cause, or the span has no control step)
  std::optional<EstimatorHealthResets> health_resets;
  // a distractor fault's frames (null for other faults, or when its run ended before the tally
  // was read): the share of the captures in its window with the distractor drawn, and drawn
  // with its centre in the image
  std::optional<double> distractor_drawn_fraction, distractor_in_image_fraction;
  std::optional<int> detections;               // detections made at capture in its window
  std::optional<int> false_detections;         // of them, on the distractor rather than the payload
  std::optional<double> false_detection_rate;  // false_detections / detections (null: none)
  // the span: to the start of the next fault that starts after this one's end, or the run's end
  double span_end_s = 0.0;
};

/// Summary statistics of a sample: median, 99th percentile, max.
struct Quantiles {
  double median = 0.0, p99 = 0.0, max = 0.0;
};

/// One vehicle's metrics, alone or in a team (metrics.json `vehicles`, a team's also
/// `team.vehicles`).
struct VehicleMetrics {
  double slack_time_s = 0.0;  // its cable slack (true)
  int slack_events = 0;       // slack intervals of its cable (chatter under 30 ms ignored)
  int retaut_count = 0;       // slack to taut
  // the extremes, over every physics step of the log's span (PhysicsRateExtremes)
  double tilt_max_deg = 0.0;              // largest angle between its body z axis and the world's
  double cable_tension_max_N = 0.0;       // largest true tension of its cable
  double mixer_saturated_fraction = 0.0;  // share of its rate loop's allocations that fell short
  int control_failures = 0;               // updates that were not a plan or a recovery
  Quantiles solve_ms;                     // its controller's update wall time
  // its payload camera: frames, and the share with the true payload centre in view (null
  // without a camera)
  int camera_frames = 0;
  std::optional<double> payload_in_fov_fraction;
};

/// The team's metrics of a team run (metrics.json `team`; docs/cooperative.md).
struct TeamMetrics {
  double min_vehicle_separation_m = 0.0;  // smallest distance between two vehicles' centres
  double payload_tilt_max_deg = 0.0;      // largest angle between the payload's z axis and up
  bool onboard = false;  // each vehicle flew on its onboard estimate of its own state
  bool cameras = false;  // each vehicle flew its payload camera
};

/// The metrics.json contract (docs/design.md section 8) plus extensions.
struct Metrics {
  std::string scenario, controller, camera;
  unsigned long seed = 0;
  double sim_time_s = 0.0, wall_time_s = 0.0;
  int control_steps = 0;  // log rows; 0: tracking metrics are written as null
  bool crashed = false;
  std::optional<double> crash_time_s;
  std::optional<std::string> crash_reason;
  // RMSE against the reference, per axis. Payload: over taut time only when the run had slack
  // intervals (payload_rmse_over = "taut_time"), else over the whole run ("whole_run").
  Eigen::Vector3d payload_rmse_m = Eigen::Vector3d::Zero();
  // the same with the onboard estimate in place of the truth (same samples): what a flight with
  // no external ground truth can report, the basis of the paper's Table I
  Eigen::Vector3d payload_rmse_est_m = Eigen::Vector3d::Zero();
  std::string payload_rmse_over = "whole_run";
  double payload_rmse_from_s = 0.0;  // payload RMSE from this time on (a reference's ramp end)
  Eigen::Vector3d quad_rmse_m = Eigen::Vector3d::Zero();
  double quad_position_deviation_max_m = 0.0;  // max |p_Q - p_Q,ref| over the run
  double payload_max_speed_mps = 0.0;
  double slack_time_s = 0.0;   // true slack time
  double mode_accuracy = 1.0;  // share of control steps with est mode = true mode
  std::optional<double> slack_detection_latency_mean_s, slack_detection_latency_max_s;
  int slack_events = 0, slack_events_missed = 0;
  double payload_in_fov_fraction = 1.0;   // share of camera frames with the payload centre in view
  double payload_lost_time_s = 0.0;       // time the estimator reported the payload lost
  double mixer_saturated_fraction = 0.0;  // share of rate-loop allocations that fell short
  int camera_frames = 0, detections = 0;
  // false: a separate stack that uses no pixels flew the rendered camera's run without it (no
  // frame rendered or sent): camera "none", and the camera's counts and timings are null
  bool camera_flown = true;
  int retaut_count = 0;
  // lowest quad z velocity and highest |w_B| within 0.5 s of a re-taut; none without a re-taut
  std::optional<double> retaut_quad_vz_min_mps;
  std::optional<double> retaut_peak_body_rate_radps;
  Quantiles mpc_solve_ms;
  int mpc_failures = 0;  // updates with QP failure, non-finite or fallback (capped plans fly)
  double closed_loop_cost = 0.0;                 // sum of the controller's plan costs
  Quantiles detector_ms;                         // per rendered frame, detection only
  std::optional<double> camera_region_fraction;  // rendered frames done in a region only
  Quantiles render_ms;                           // per rendered frame: pinhole render and read-out
  Quantiles image_model_ms;                      // per rendered frame: blur, distortion, PSF, noise
  std::optional<std::string> run_error;          // the run stopped on an exception (results kept)
  std::string world_profile = "ideal";           // realism profile of the simulated world
  std::string flight_stack = "in_process";  // what flew: in process, or a separate stack's name
  // smallest payload-to-vehicle surface distance over the run (m; negative: they overlapped)
  double payload_quad_min_distance_m = 0.0;
  // contact episodes: payload-body, payload-rotor, payload-ground, quadrotor-ground,
  // payload-gripper rod (while the gripper does not hold it)
  int contacts_payload_body = 0, contacts_payload_rotor = 0, contacts_payload_ground = 0,
      contacts_quad_ground = 0, contacts_payload_gripper = 0;
  // estimator variant flown ("" with ground truth) and its published health counts at the end
  std::string estimator;
  std::vector<std::pair<std::string, double>> estimator_health;
  std::vector<FaultRecovery> faults;  // one per fault event applied (metrics.json `faults`)
  bool expect_passed = true;
  std::vector<std::string> expect_failed;  // "payload_rmse_max.x: 0.071 > 0.06"
  // one entry per vehicle, in the scenario's order (one for a single vehicle)
  std::vector<VehicleMetrics> vehicles;
  // a team run's team metrics (none: one vehicle); the single vehicle's quadrotor, camera and
  // estimator metrics are then null
  std::optional<TeamMetrics> team;
};

/// A metric a kind of run does not measure: its metrics.json key, written null, and how its
/// field in Metrics reads "not measured" (NaN; none for a count, whose null in metrics.json says
/// it), so that expect keys, sweeps and the JSON agree.
struct UnmeasuredMetric {
  const char* json_key;           // its metrics.json path, dotted ("retaut.quad_vz_min_mps"); a
                                  // list on the path (vehicles, faults) means each entry's field
  void (*mark)(Metrics* m);       // sets the field to not measured (nullptr: a count, or what the
                                  // run leaves null itself)
  bool onboard_measures = false;  // measured when the team's vehicles estimate on board
  bool camera_measures = false;   // measured when the team's vehicles fly their payload cameras
};

/// What a team run does not measure: the single vehicle's quadrotor, estimator, camera and
/// contact metrics. The one list the team runner marks and MetricsToJson writes null.
const std::vector<UnmeasuredMetric>& TeamUnmeasuredMetrics();

/// What a run whose rendered camera was not flown (a separate stack that uses no pixels) does
/// not measure: the camera's counts, share in view and timings, its own and each vehicle's. The
/// one list the run loop marks and MetricsToJson writes null.
const std::vector<UnmeasuredMetric>& CameraNotFlownMetrics();

/// Whether a team run measures the metric at this metrics.json path (dotted): false for a path
/// of TeamUnmeasuredMetrics() or inside one, but for those its vehicles' onboard estimates
/// measure when `onboard` (a fault's health flag and estimate error) and their payload cameras
/// when `cameras` (the share of frames with the payload in view).
bool TeamMeasures(const std::string& json_path, bool onboard = false, bool cameras = false);

/// Marks every metric of `unmeasured` not measured in m.
void MarkUnmeasured(const std::vector<UnmeasuredMetric>& unmeasured, Metrics* m);

/// A vehicle's extremes at the physics rate (VehicleMetrics' tilt_max_deg and
/// cable_tension_max_N), for one vehicle and a team alike: every physics step's truth is offered,
/// so a cable's snap of a few milliseconds is its peak, not whatever a control-step row caught.
void UpdateVehicleExtremes(const Eigen::Vector4d& q_WB_wxyz, double cable_tension_N,
                           VehicleMetrics* vehicle);

/// Inputs the metrics need besides the log.
struct MetricsInputs {
  std::vector<LogRow> rows;
  std::vector<bool> payload_in_fov_per_frame;
  std::vector<double> detector_ms, render_ms, image_model_ms;
  int region_frames = 0;  // rendered frames served by a region around the last detection
  int detections = 0;
  int rate_loop_steps = 0;          // allocations made by the rate loop
  int mixer_saturated_steps = 0;    // of which fell short of the demanded thrust or torque
  std::vector<FaultWindow> faults;  // the fault events applied, in time order
  bool ground_truth = false;        // the flight code flew on the true state (no estimate)
  // the vehicle's physics-rate extremes over the log's span (UpdateVehicleExtremes, the runner's)
  VehicleMetrics extremes;
};

/// How the flight code recovered from each fault window, from the log's rows (a team's as rows of
/// its payload's truth and reference): the span to the next fault, the payload's error and its
/// return within the window's bound, the estimator's flags and counts (none with ground_truth).
std::vector<FaultRecovery> FaultRecoveries(const std::vector<LogRow>& rows,
                                           const std::vector<FaultWindow>& windows,
                                           bool ground_truth);

/// Computes every metric from the log (crash fields and timing are filled by the runner).
void ComputeMetrics(const MetricsInputs& inputs, Metrics* metrics);

/// Adds each distractor fault's frame tally (sim::Faults::FrameTallies, in the order injected) to
/// the metrics entry of its fault event (the first distractor entry starting at its start);
/// returns whether any was added.
bool AddFaultFrameTallies(const std::vector<sim::FaultFrameTally>& tallies, Metrics* metrics);

/// Checks the scenario's expect bounds; fills expect_passed / expect_failed.
void CheckExpectations(const ExpectSpec& expect, Metrics* metrics);

/// metrics.json text (keys of docs/design.md section 8; `wall_time_s` and `*_ms` are the only
/// fields that differ between identical runs).
std::string MetricsToJson(const Metrics& metrics);

/// The q-quantile (q in [0, 1]) of a sample, linear between the closest ranks (Hyndman and Fan
/// type 7); NaN for an empty sample or q outside [0, 1]. The one quantile of metrics and sweeps.
double Quantile(std::vector<double> values, double q);

/// Median, 99th percentile and max of a sample by Quantile (empty sample -> zeros).
Quantiles ComputeQuantiles(std::vector<double> values);

/// Angle between a body's z axis and the world's (deg), from its attitude quaternion (w, x, y, z).
double TiltDeg(const Eigen::Vector4d& q_wxyz);

/// Slack intervals [start, end) of a cable's modes sampled at times_s (same length), chatter
/// shorter than 30 ms ignored.
std::vector<std::pair<double, double>> SlackIntervals(const std::vector<double>& times_s,
                                                      const std::vector<CableMode>& modes);

/// Whether a control step at time_s counts towards the payload RMSE, for one vehicle and a team
/// alike: from from_s on (1 ns rounding margin) and outside every slack interval (`slack`: the
/// run's true slack intervals, a team's those with any cable slack).
bool InPayloadRmse(double time_s, const std::vector<std::pair<double, double>>& slack,
                   double from_s);

/// "taut_time" when the run had slack intervals (the payload RMSE leaves them out), else
/// "whole_run": metrics.json's payload_rmse_over.
const char* PayloadRmseOver(const std::vector<std::pair<double, double>>& slack);

/// Slack intervals of the true mode in the log (SlackIntervals of its rows).
std::vector<std::pair<double, double>> TrueSlackIntervals(const std::vector<LogRow>& rows);

/// Creates an output directory and its parents; throws InputError (key --out) if it cannot.
void MakeOutputDir(const std::string& dir);

/// Writes log.csv (one row per control step).
void WriteLogCsv(const std::string& path, const std::vector<LogRow>& rows);

/// Writes a team run's log.csv for `vehicles` vehicles (one row per control step; columns in
/// docs/cooperative.md).
void WriteTeamLogCsv(const std::string& path, const std::vector<TeamLogRow>& rows, int vehicles);

}  // namespace hpa
