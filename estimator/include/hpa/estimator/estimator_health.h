#pragma once
// Health of the onboard estimator, published rather than discarded: what each filter did with
// its inputs (accepted, gated, forced, refused) and the mode detector's state, so a bad flight
// can be explained from its log.

#include <string>
#include <utility>
#include <vector>

#include "hpa/estimator/filter_status.h"

namespace hpa {

/// The health check's re-initialisations of the filters, by the cause that triggered each.
struct EstimatorHealthResets {
  int quad_non_finite = 0;     // the quadrotor filter non-finite: restarted from the last VIO
  int payload_non_finite = 0;  // the payload estimate or a payload filter's covariance non-finite
  int payload_speed = 0;       // payload speed relative to the vehicle past any push's
  int cable_length = 0;        // payload farther from the vehicle than the cable and its stretch

  /// The sum over the causes.
  int Total() const { return quad_non_finite + payload_non_finite + payload_speed + cable_length; }
};

/// Running counts of the estimator's filters since start, plus its current mode state.
struct EstimatorHealth {
  FilterCounts quad_filter;              // IMU predictions and VIO updates
  FilterCounts cable_ekf;                // cable predictions and detection updates while taut
  FilterCounts payload_tracker;          // detection updates while slack
  int detections_lost = 0;               // camera frames in which the payload was not found
  int detections_non_finite = 0;         // detections refused for a NaN/Inf time or position
  int thrust_commands_non_finite = 0;    // thrust commands refused (the last one is kept)
  int slack_entries = 0;                 // taut-to-slack switches (payload tracker restarted)
  int slack_entries_by_tension = 0;      // of them, flagged first by the tension cue
  int retaut_restarts = 0;               // slack-to-taut switches (cable EKF restarted)
  int retaut_restarts_by_tension = 0;    // of them, by the tension cue with the payload unseen
  int cable_reinitialisations = 0;       // cable EKF restarted from detections it kept rejecting
  EstimatorHealthResets health_resets;   // the health check's re-initialisations, by cause
  bool slack = false;                    // current estimated mode
  double filtered_cable_length_m = 0.0;  // the mode detector's low-passed cable length

  /// Gate rejections summed over the three filters.
  int RejectedUpdates() const;
  /// Forced accepts (updates fused over the gate after a run of rejections) over the filters.
  int ForcedAccepts() const;
  /// Every field as (name, value) in a fixed order: the totals rejected_updates and resets
  /// (forced accepts), each filter's counts prefixed quad_, cable_ and tracker_, then the rest
  /// (the health check's resets prefixed health_resets_, with their total).
  std::vector<std::pair<std::string, double>> Fields() const;
};

}  // namespace hpa
