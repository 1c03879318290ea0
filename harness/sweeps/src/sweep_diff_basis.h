#pragma once
// sweep-diff's check that both runs of a pair flew on the same information: the estimation basis
// (the true state or an estimate, and what the estimate was made from) each run's metrics.json
// records.

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace hpa {

/// The estimation basis a run's metrics.json records ("ground truth", "estimate, analytic
/// camera", "estimate, rendered camera", a team's "estimate, vehicle state motion_capture", ...),
/// read from its `camera` (ground_truth | render | analytic | none | mocap) and a team's
/// `team.vehicle_state`; nullopt when the record has no `camera` (an older hpa, no metrics).
std::optional<std::string> EstimationBasis(const nlohmann::json& metrics);

/// The lines "What differs" gets from the pairs' bases (A's, B's; nullopt where not recorded):
/// each combination of differing bases with its pair count and a warning that the pairing
/// compares flights given different information (a note without a warning when a stack only
/// declined the rendered frames it was offered), and a note when one side records no basis.
/// Empty when every pair that records both flew on the same basis.
std::vector<std::string> DescribeBasisDifferences(
    const std::vector<std::pair<std::optional<std::string>, std::optional<std::string>>>& bases);

}  // namespace hpa
