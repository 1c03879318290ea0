#include "hpa/estimator/estimator_health.h"

namespace hpa {

int EstimatorHealth::RejectedUpdates() const {
  return quad_filter.rejected_updates + cable_ekf.rejected_updates +
         payload_tracker.rejected_updates;
}

int EstimatorHealth::ForcedAccepts() const {
  return quad_filter.forced_accepts + cable_ekf.forced_accepts + payload_tracker.forced_accepts;
}

std::vector<std::pair<std::string, double>> EstimatorHealth::Fields() const {
  std::vector<std::pair<std::string, double>> fields = {{"rejected_updates", RejectedUpdates()},
                                                        {"resets", ForcedAccepts()}};
  for (const auto& [prefix, counts] :
       {std::pair<std::string, const FilterCounts*>{"quad_", &quad_filter},
        {"cable_", &cable_ekf},
        {"tracker_", &payload_tracker}}) {
    for (auto& field : counts->Fields(prefix)) fields.push_back(std::move(field));
  }
  fields.insert(fields.end(),
                {{"detections_lost", detections_lost},
                 {"detections_non_finite", detections_non_finite},
                 {"thrust_commands_non_finite", thrust_commands_non_finite},
                 {"slack_entries", slack_entries},
                 {"slack_entries_by_tension", slack_entries_by_tension},
                 {"retaut_restarts", retaut_restarts},
                 {"retaut_restarts_by_tension", retaut_restarts_by_tension},
                 {"cable_reinitialisations", cable_reinitialisations},
                 {"health_resets", health_resets.Total()},
                 {"health_resets_quad_non_finite", health_resets.quad_non_finite},
                 {"health_resets_payload_non_finite", health_resets.payload_non_finite},
                 {"health_resets_payload_speed", health_resets.payload_speed},
                 {"health_resets_cable_length", health_resets.cable_length},
                 {"slack", slack ? 1.0 : 0.0},
                 {"filtered_cable_length_m", filtered_cable_length_m}});
  return fields;
}

}  // namespace hpa
