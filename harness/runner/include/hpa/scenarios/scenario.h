#pragma once
// A scenario file (docs/design.md section 5) loaded and validated: unknown keys, wrong types and
// out-of-range values are InputErrors naming the file and the key path.

#include <Eigen/Core>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "hpa/controller/controller.h"
#include "hpa/controller/reference.h"
#include "hpa/controller/reference_spec.h"
#include "hpa/scenarios/events.h"
#include "hpa/scenarios/world_profile_yaml.h"
#include "hpa/sim/world_profile.h"

namespace hpa {

/// Regression bounds (keys of expect_keys.h); `hpa run` exits 1 if any fails. Unset bounds are
/// not checked.
struct ExpectSpec {
  std::map<std::string, std::vector<double>> bounds;  // expect key -> bound (booleans as 0 / 1)
  /// True if the scenario sets `key`.
  bool Has(const std::string& key) const { return bounds.count(key) > 0; }
};

/// Estimation block: where flight code gets its state from.
struct EstimationSpec {
  std::string camera = "render";      // render (OSMesa + detector) | analytic (projection + noise)
  bool ground_truth = false;          // true: flight code sees the true state
  double camera_latency_s = 0.03;     // capture to detection delivery
  double detector_noise_scale = 1.0;  // analytic camera only: scale on the measured noise
  bool slack_tension_cue = true;      // hybrid estimator: also flag slack from the IMU tension
  bool camera_randomize = false;      // floor and lighting of the rendered camera vary by seed
  // estimator variant (estimator_registry.h); unset: the one the controller is registered with
  std::optional<std::string> estimator;
  // a team vehicle's own state, without the ground-truth switch: "motion_capture" (RotorTM's
  // experiments) or "onboard" (its quadrotor filter on its own IMU and VIO); a single vehicle's
  // is always its onboard estimator's
  std::string vehicle_state = "motion_capture";
};

/// One vehicle of a team scenario (the `vehicles:` list): its cable, where the cable holds the
/// payload, and where it starts.
struct VehicleSpec {
  double cable_length_m = 0.5;
  Eigen::Vector3d p_PA_P_m = Eigen::Vector3d::Zero();  // attachment point, payload frame (3)
  // how much closer than its cable's length the vehicle starts above its attachment point (0:
  // taut; a lift starts its cables slack)
  double start_slack_m = 0.0;
};

/// A team scenario's payload and vehicles (docs/cooperative.md). No vehicles: the single-vehicle
/// world of every other scenario.
struct TeamSpec {
  std::vector<VehicleSpec> vehicles;  // 1 to 3 when set
  double payload_mass_kg = 0.2;
  Eigen::Vector3d payload_inertia_P_kgm2{1e-3, 1e-3, 1e-3};  // diagonal, payload frame (3)
  // the payload starts resting on the ground below the reference's start (a lift) instead of at
  // it
  bool payload_on_ground = false;
  // each vehicle flies the single vehicle's payload camera (the scenario's estimation.camera:
  // rendered or analytic); without it the payload is seen by motion capture alone
  bool payload_cameras = false;
  /// Whether the scenario flies a team.
  bool IsTeam() const { return !vehicles.empty(); }
};

/// A whole scenario file.
struct Scenario {
  std::string file;  // where it was loaded from ("" if built in code)
  std::string name;
  double duration_s = 10.0;
  unsigned long seed = 1;
  // world realism profile; a scenario file gets `flight` unless it says `world.profile: ideal`,
  // a Scenario built in code the ideal world
  sim::WorldProfile world;
  RateLoopSpec rate_loop;  // the flight code's body-rate loop (the profile's rate_loop section)
  std::optional<double> world_payload_mass_kg;  // world-only overrides (model mismatch)
  std::optional<double> world_cable_length_m;
  // the `params:` block as YAML text ("" none): values of params.yaml changed for this
  // scenario, for the flight code's model and the world alike
  std::string params_yaml;
  ControllerConfig controller;
  EstimationSpec estimation;
  ReferenceSpec reference;
  std::vector<EventSpec> events;
  ExpectSpec expect;
  TeamSpec team;  // `payload:` and `vehicles:` (empty: one vehicle)
};

/// The estimator variant a scenario flies with: estimation.estimator, else the default of the
/// controller's registration.
std::string EstimatorOf(const Scenario& scenario);

/// Checks a controller type against the registry (a team scenario's: TeamControllerNames());
/// throws InputError (file, key) listing the names it may be.
void CheckControllerType(const std::string& type, const std::string& file, const std::string& key,
                         bool team = false);

/// One change to a scenario file before it is validated: a dotted key path (e.g.
/// events.1.impulse.2) and the value's YAML text (e.g. 0.5, [0, 0, 1], hpa_mpc).
using ScenarioSet = std::pair<std::string, std::string>;

/// Loads and validates a scenario file with `sets` applied in order (the `--set` of the CLI and
/// a sweep run's drawn values); throws InputError naming the file, or `origin` and the key for a
/// bad set.
Scenario LoadScenario(const std::string& path, const std::vector<ScenarioSet>& sets = {},
                      const std::string& origin = "--set");

/// LoadScenario from the scenario's text (a sweep's snapshot of its base); `path` names it in
/// messages. `reference_csv_text`, when given, is a csv reference's file text (a run.json's
/// snapshot), parsed instead of reading the file.
Scenario LoadScenarioText(const std::string& text, const std::string& path,
                          const std::vector<ScenarioSet>& sets = {},
                          const std::string& origin = "--set",
                          const std::optional<std::string>& reference_csv_text = std::nullopt);

/// Whether `name` can name an output folder: 1 to 64 of A-Z a-z 0-9 _ - ., not starting with
/// '.' (no separators, nothing a shell mangles). A scenario's name and compare's stack names.
bool IsSafeName(const std::string& name);

/// Splits a `--set PATH=VALUE` argument; throws InputError if it has no PATH= part.
ScenarioSet ParseSetArgument(const std::string& text);

/// Validates an already parsed YAML node as a scenario (used by sweeps after applying `vary`);
/// `reference_csv_text` as for LoadScenarioText.
Scenario ParseScenario(const class YamlMap& root,
                       const std::optional<std::string>& reference_csv_text = std::nullopt);

/// The payload cameras estimation.camera (and --camera) may name.
const std::vector<std::string>& CameraNames();

/// The params a scenario flies with: `params` with the scenario's `params:` block applied
/// (validated when the scenario was loaded).
Params ScenarioParams(const Scenario& scenario, const Params& params);

/// Builds the payload reference of a scenario.
std::shared_ptr<Reference> MakeReference(const Scenario& scenario, const Params& params);

}  // namespace hpa
