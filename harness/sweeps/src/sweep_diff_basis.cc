#include "harness/sweeps/src/sweep_diff_basis.h"

#include <map>

namespace hpa {
namespace {

constexpr char kRendered[] = "estimate, rendered camera";
constexpr char kNoPixels[] = "estimate, no camera frames (the stack uses no pixels)";

// Whether two bases differ only in a stack's declining the rendered frames it was offered.
bool OnlyPixelsDeclined(const std::string& a, const std::string& b) {
  return (a == kRendered && b == kNoPixels) || (a == kNoPixels && b == kRendered);
}

}  // namespace

std::optional<std::string> EstimationBasis(const nlohmann::json& metrics) {
  if (!metrics.is_object() || !metrics.contains("camera") || !metrics["camera"].is_string()) {
    return std::nullopt;
  }
  const std::string camera = metrics["camera"].get<std::string>();
  if (camera == "ground_truth") return "ground truth";
  // a team: each vehicle's own state from motion capture or its onboard estimate
  const auto team = metrics.find("team");
  if (team != metrics.end() && team->is_object()) {
    const auto state = team->find("vehicle_state");
    const std::string source =
        state != team->end() && state->is_string() ? state->get<std::string>() : camera;
    return "estimate, vehicle state " + source;
  }
  if (camera == "render") return kRendered;
  if (camera == "analytic") return "estimate, analytic camera";
  if (camera == "none") return kNoPixels;
  return "estimate, camera " + camera;
}

std::vector<std::string> DescribeBasisDifferences(
    const std::vector<std::pair<std::optional<std::string>, std::optional<std::string>>>& bases) {
  std::map<std::pair<std::string, std::string>, int> differing;  // (A's, B's) -> pairs
  int compared = 0, unrecorded_a = 0, unrecorded_b = 0;
  for (const auto& [a, b] : bases) {
    unrecorded_a += !a;
    unrecorded_b += !b;
    if (!a || !b) continue;
    ++compared;
    if (*a != *b) ++differing[{*a, *b}];
  }
  std::vector<std::string> lines;
  for (const auto& [ab, pairs] : differing) {
    const std::string head = "estimation basis: " + ab.first + " (A) vs " + ab.second +
                             " (B), in " + std::to_string(pairs) + " of " +
                             std::to_string(compared) + " pairs: ";
    // a stack that declared it uses no pixels was offered the same camera: a note, no warning
    lines.push_back(
        head + (OnlyPixelsDeclined(ab.first, ab.second)
                    ? "both were given the rendered camera; a stack that declared it uses no "
                      "pixels was sent no frame (its own choice, not a different offering)"
                    : "WARNING, the pairing compares flights given different information, not the "
                      "controller or stack alone (give both sides the same "
                      "estimation.ground_truth, estimation.camera and estimation.vehicle_state, "
                      "e.g. --set estimation.ground_truth=false on both)"));
  }
  // a side that records no basis (an older hpa): say the check could not be made
  if (!bases.empty() && (unrecorded_a > 0) != (unrecorded_b > 0)) {
    lines.push_back(std::string("estimation basis: not recorded in ") +
                    (unrecorded_a > 0 ? "A" : "B") + "'s runs (" +
                    std::to_string(unrecorded_a > 0 ? unrecorded_a : unrecorded_b) +
                    "): whether both sides flew on the same information is not checked there");
  }
  return lines;
}

}  // namespace hpa
