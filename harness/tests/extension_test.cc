// Extending by registration, each path proven end to end: an event type and an expect key
// defined in this file alone, registered with one call each, used by a scenario's YAML and run
// through the real `hpa run` (the controller path: toy_controller_test.cc; the estimator path:
// estimator_registry_test.cc).

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hpa/models/yaml_reader.h"
#include "hpa/scenarios/cli.h"
#include "hpa/scenarios/events.h"
#include "hpa/scenarios/expect_keys.h"
#include "hpa/scenarios/metrics.h"
#include "hpa/sim/world.h"
#include "models/tests/temp_dir.h"

namespace hpa {
namespace {

// A sideways push on the quadrotor of `impulse` N s: a new event type in one struct.
struct SidewaysPush final : EventAction {
  double impulse_Ns = 0.0;
  void Apply(sim::World* world) const override {
    world->disturbances().ApplyImpulse(sim::Body::kQuadrotor, Eigen::Vector3d(impulse_Ns, 0, 0));
  }
};

int Hpa(std::vector<std::string> args) {
  args.insert(args.begin(), "hpa");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  return HpaMain(static_cast<int>(argv.size()), argv.data());
}

void RegisterOnce() {
  bool registered = false;
  for (const EventRegistration& r : EventTypes()) registered = registered || r.name == "push_x";
  if (registered) return;
  // the one registration call a new event type needs
  RegisterEventType({"push_x", "a sideways push of `impulse` N s on the quadrotor (test)",
                     [](const YamlMap& map) {
                       auto push = std::make_shared<SidewaysPush>();
                       push->impulse_Ns = map.Number("impulse", 0.0, 10.0);
                       return std::shared_ptr<const EventAction>(push);
                     }});
  // and the one a new expect key needs: the largest deviation allowed, under a new name
  ExpectKey key{"deviation_at_most",
                "quad_position_deviation_max_m",
                "metric <= bound",
                "m",
                "largest quadrotor deviation (test)",
                1,
                0.0,
                10.0,
                false,
                {}};
  key.check = [](const Metrics& m, const std::vector<double>& bound) {
    return m.quad_position_deviation_max_m > bound[0]
               ? std::vector<std::string>{"deviation_at_most: over the bound"}
               : std::vector<std::string>{};
  };
  RegisterExpectKey(key);
}

std::string Scenario(double push_Ns, double bound_m) {
  return "name: pushed\nduration: 2.0\nworld: {profile: ideal}\n"
         "controller: {type: geometric}\n"
         "estimation: {ground_truth: true, camera: analytic}\n"
         "reference: {type: hover, payload_position: [0, 0, 0.7]}\n"
         "events: [{at: 0.5, type: push_x, impulse: " +
         std::to_string(push_Ns) + "}]\nexpect: {deviation_at_most: " + std::to_string(bound_m) +
         "}\n";
}

TEST(ExtensionTest, ARegisteredEventTypeAndExpectKeyRunThroughHpaRun) {
  RegisterOnce();
  const std::string dir = TestTempDir();
  // no push: the hover holds within 5 cm and the new key passes
  std::ofstream(dir + "calm.yaml") << Scenario(0.0, 0.05);
  EXPECT_EQ(Hpa({"run", dir + "calm.yaml", "--out", dir + "calm", "--quiet"}), 0);
  // a 0.5 N s push moves the vehicle well beyond 5 cm: the event acted, and the key failed
  std::ofstream(dir + "pushed.yaml") << Scenario(0.5, 0.05);
  EXPECT_EQ(Hpa({"run", dir + "pushed.yaml", "--out", dir + "pushed", "--quiet"}), 1);
  std::ifstream in(dir + "pushed/metrics.json");
  const nlohmann::json m = nlohmann::json::parse(in);
  EXPECT_GT(m["quad_position_deviation_max_m"].get<double>(), 0.05);
  ASSERT_EQ(m["expect"]["failed"].size(), 1u);
  EXPECT_EQ(m["expect"]["failed"][0], "deviation_at_most: over the bound");
  // the new event's own keys are validated like the built-ins'
  std::ofstream(dir + "bad.yaml") << Scenario(50.0, 0.05);
  EXPECT_EQ(Hpa({"run", dir + "bad.yaml", "--out", dir + "bad", "--quiet"}), 2);
}

}  // namespace
}  // namespace hpa
