// Golden covers every path a change can touch: each registered controller, estimator variant,
// OCP solver and QP method, reference type, event type (an impulse on either body), world profile
// and world-profile part, and each flight-code switch off its default, is flown by at least one
// golden scenario. A change confined to a path no golden scenario flies would pass
// `golden --exact`; this test fails first, naming the path and what to add.

#include <gtest/gtest.h>

#include <functional>
#include <set>
#include <string>
#include <vector>

#include "hpa/controller/controller_registry.h"
#include "hpa/controller/rti_solver.h"
#include "hpa/controller/team_controller.h"
#include "hpa/estimator/estimator_registry.h"
#include "hpa/models/data_dir.h"
#include "hpa/scenarios/events.h"
#include "hpa/scenarios/golden.h"
#include "hpa/scenarios/reference_types.h"
#include "hpa/scenarios/scenario.h"
#include "hpa/scenarios/world_profile_yaml.h"

namespace hpa {
namespace {

// One part of the world profile, and whether a scenario's world has it on.
struct WorldPart {
  std::string name;
  std::function<bool(const Scenario&)> on;
};

// Every part of sim::WorldProfile (one entry per section of the profile file, the wind split
// into its steady and its gust part) and the flight code's PX4 rate loop.
const std::vector<WorldPart>& WorldParts() {
  static const std::vector<WorldPart> parts = {
      {"contact", [](const Scenario& s) { return s.world.contact.enabled; }},
      {"actuation", [](const Scenario& s) { return s.world.actuation.enabled; }},
      {"latency",
       [](const Scenario& s) {
         const auto& l = s.world.latency;
         return l.compute_s > 0 || l.transport_s > 0 || l.estimate_s > 0;
       }},
      {"mismatch", [](const Scenario& s) { return s.world.mismatch.enabled; }},
      {"aero", [](const Scenario& s) { return s.world.aero.enabled; }},
      {"wind.mean",
       [](const Scenario& s) {
         const auto& w = s.world.wind;
         return w.mean_x_mps != 0 || w.mean_y_mps != 0 || w.mean_z_mps != 0;
       }},
      {"wind.gust (Dryden)", [](const Scenario& s) { return s.world.wind.gust_sigma_mps > 0; }},
      {"vio", [](const Scenario& s) { return s.world.vio.enabled; }},
      {"imu", [](const Scenario& s) { return s.world.imu.enabled; }},
      {"camera.exposure", [](const Scenario& s) { return s.world.camera.exposure_s > 0; }},
      {"camera.noise", [](const Scenario& s) { return s.world.camera.noise; }},
      {"rate_gyro", [](const Scenario& s) { return s.world.rate_gyro.enabled; }},
      {"rate_loop.px4", [](const Scenario& s) { return s.rate_loop.px4; }},
  };
  return parts;
}

// The flown controller's setting `key` as text, or "" when it declares none.
std::string SettingOf(const Scenario& s, const std::string& key) {
  const SettingDecl* d = FindSetting(FindController(s.controller.type)->settings, key);
  return d == nullptr ? "" : SettingText(SettingOr(s.controller.settings, *d));
}

// What one scenario flies, as "kind: name" entries.
std::set<std::string> PathsOf(const Scenario& s) {
  if (s.team.IsTeam()) {
    // a team: its controller on every vehicle, its reference and events (no estimator, camera
    // or controller settings: each vehicle flies on motion capture)
    std::set<std::string> paths = {"team controller: " + s.controller.type,
                                   "reference: " + s.reference.type};
    for (const EventSpec& e : s.events) {
      if (const auto* impulse = dynamic_cast<const ImpulseEvent*>(e.action.get())) {
        paths.insert(std::string("team event: impulse on ") +
                     (impulse->on_payload ? "the payload" : "a vehicle"));
      }
    }
    if (s.team.payload_on_ground) paths.insert("team: payload lifted from the ground");
    return paths;
  }
  std::set<std::string> paths = {
      "controller: " + s.controller.type,
      "estimator: " + EstimatorOf(s),
      "reference: " + s.reference.type,
      "world profile: " + s.world.name,
      "camera: " + std::string(s.estimation.ground_truth ? "ground_truth" : s.estimation.camera),
  };
  const std::string solver = SettingOf(s, "solver");
  if (!solver.empty()) paths.insert("solver: " + solver);
  if (solver == "rti") paths.insert("qp_method: " + SettingOf(s, "qp_method"));
  if (SettingOf(s, "predict_retaut") == "true") {
    paths.insert("switch: controller.predict_retaut true");
  }
  if (!s.estimation.slack_tension_cue) paths.insert("switch: estimation.slack_tension_cue false");
  if (s.estimation.camera_randomize) paths.insert("switch: estimation.camera_randomize true");
  for (const EventSpec& e : s.events) {
    paths.insert("event: " + e.type);
    if (const auto* impulse = dynamic_cast<const ImpulseEvent*>(e.action.get())) {
      paths.insert(std::string("event: impulse on the ") +
                   (impulse->on_payload ? "payload" : "quadrotor"));
    }
  }
  for (const WorldPart& part : WorldParts()) {
    if (part.on(s)) paths.insert("world part: " + part.name);
  }
  return paths;
}

// Whether a registration was made by a test of this binary (its description ends "(test)"): a
// test's extension is no shipped path (the whole binary run at once holds them).
bool ByATest(const std::string& description) {
  const std::string mark = "(test)";
  return description.size() >= mark.size() &&
         description.compare(description.size() - mark.size(), mark.size(), mark) == 0;
}

// Every path the registries and declarations say exists.
std::set<std::string> RegisteredPaths() {
  std::set<std::string> paths;
  for (const ControllerRegistration& c : Controllers()) {
    if (!ByATest(c.description)) paths.insert("controller: " + c.name);
  }
  for (const std::string& n : EstimatorNames()) paths.insert("estimator: " + n);
  for (const std::string& n : OcpSolverNames()) paths.insert("solver: " + n);
  for (const std::string& n : RtiQpMethodNames()) paths.insert("qp_method: " + n);
  for (const ReferenceType& t : ReferenceTypes()) {
    if (!ByATest(t.description)) paths.insert("reference: " + t.name);
  }
  for (const std::string& n : WorldProfileNames()) paths.insert("world profile: " + n);
  for (const char* camera : {"render", "analytic", "ground_truth"}) {
    paths.insert(std::string("camera: ") + camera);
  }
  for (const EventRegistration& e : EventTypes()) {
    if (!ByATest(e.description)) paths.insert("event: " + e.name);
  }
  paths.insert("event: impulse on the payload");
  paths.insert("event: impulse on the quadrotor");
  paths.insert("switch: controller.predict_retaut true");
  paths.insert("switch: estimation.slack_tension_cue false");
  paths.insert("switch: estimation.camera_randomize true");
  for (const WorldPart& part : WorldParts()) paths.insert("world part: " + part.name);
  for (const std::string& n : TeamControllerNames()) paths.insert("team controller: " + n);
  paths.insert("team event: impulse on a vehicle");
  paths.insert("team: payload lifted from the ground");
  return paths;
}

TEST(GoldenCoverageTest, EveryRegisteredPathIsFlownByAGoldenScenario) {
  std::set<std::string> flown;
  for (const std::string& name : GoldenScenarioNames()) {
    const std::set<std::string> paths =
        PathsOf(LoadScenario(DataPath("scenarios") + "/" + name + ".yaml"));
    flown.insert(paths.begin(), paths.end());
  }
  for (const std::string& path : RegisteredPaths()) {
    EXPECT_TRUE(flown.count(path))
        << path << ": no golden scenario flies it; add a short scenario to scenarios/ci/ that "
        << "does (then `hpa golden --update --reason ...`)";
  }
}

// The check sees what it claims to: a scenario's impulse body, solver and switches.
TEST(GoldenCoverageTest, PathsOfAScenarioNameWhatItFlies) {
  const Scenario s =
      LoadScenario(DataPath("scenarios") + "/line_impulse.yaml",
                   {{"controller.solver", "nlopt"}, {"estimation.slack_tension_cue", "false"}});
  const std::set<std::string> paths = PathsOf(s);
  EXPECT_TRUE(paths.count("solver: nlopt"));
  EXPECT_FALSE(paths.count("qp_method: structured"));  // nlopt has no RTI QP
  EXPECT_TRUE(paths.count("switch: estimation.slack_tension_cue false"));
  EXPECT_TRUE(paths.count("event: impulse on the payload"));
  EXPECT_TRUE(paths.count("reference: line"));
}

}  // namespace
}  // namespace hpa
