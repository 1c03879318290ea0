#include "hpa/scenarios/scenario.h"

#include <dirent.h>
#include <gtest/gtest.h>

#include <fstream>

#include "hpa/models/input_error.h"
#include "models/tests/temp_dir.h"

namespace hpa {
namespace {

const std::string kDir = std::string(HPA_SOURCE_DIR) + "/scenarios";

std::string Write(const std::string& name, const std::string& text) {
  const std::string path = TestTempDir() + name;
  std::ofstream(path) << text;
  return path;
}

// Expects LoadScenario to throw an InputError whose message contains every fragment.
void ExpectError(const std::string& text, const std::vector<std::string>& fragments) {
  const std::string path = Write("bad.yaml", text);
  try {
    LoadScenario(path);
    FAIL() << "expected an InputError for:\n" << text;
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    for (const auto& f : fragments) EXPECT_NE(msg.find(f), std::string::npos) << msg;
  }
}

const char* kMinimal = "name: t\nduration: 1.0\n";

TEST(ScenarioTest, EveryShippedScenarioLoads) {
  int loaded = 0;
  for (const std::string sub : {"", "/ci"}) {
    DIR* dir = opendir((kDir + sub).c_str());
    ASSERT_NE(dir, nullptr);
    while (dirent* e = readdir(dir)) {
      const std::string name = e->d_name;
      if (name.size() < 5 || name.substr(name.size() - 5) != ".yaml") continue;
      EXPECT_NO_THROW(LoadScenario(kDir + sub + "/" + name)) << name;
      ++loaded;
    }
    closedir(dir);
  }
  EXPECT_GE(loaded, 2);
}

TEST(ScenarioTest, ParsesTheDesignExample) {
  const Scenario s = LoadScenario(kDir + "/hover_gripper_pull.yaml");
  EXPECT_EQ(s.name, "hover_gripper_pull");
  EXPECT_EQ(s.controller.type, "hpa_mpc");
  ASSERT_EQ(s.events.size(), 4u);
  EXPECT_EQ(s.events[1].type, "gripper_move");
  const auto* move = dynamic_cast<const GripperMoveEvent*>(s.events[1].action.get());
  ASSERT_NE(move, nullptr);
  EXPECT_DOUBLE_EQ(move->to_W_m.z(), 0.95);
  EXPECT_TRUE(s.expect.Has("crashed"));
}

TEST(ScenarioTest, DefaultsWhenBlocksAreLeftOut) {
  const Scenario s = LoadScenario(Write("min.yaml", kMinimal));
  EXPECT_EQ(s.controller.type, "hpa_mpc");
  EXPECT_EQ(s.estimation.camera, "render");
  EXPECT_FALSE(s.estimation.ground_truth);
  EXPECT_EQ(s.reference.type, "hover");
}

// world.cable_length and world.payload_mass take params.yaml's declared range for the field
// they replace (one range, as the world's own check and the mismatch draw use it).
TEST(ScenarioTest, WorldOverridesTakeParamsDeclaredRange) {
  const ParamDecl<Params>& l = FindParamDecl(ParamsTables(), &Params::cable_length_m);
  const std::string world = std::string(kMinimal) + "world:\n  cable_length: ";
  EXPECT_EQ(*LoadScenario(Write("long.yaml", world + ParamValueText(l.max) + "\n"))
                 .world_cable_length_m,
            l.max);
  ExpectError(world + ParamValueText(2 * l.max) + "\n",
              {"world.cable_length", ParamValueText(l.min), ParamValueText(l.max)});
  ExpectError(world + "0.0\n", {"world.cable_length"});
  const ParamDecl<Params>& m = FindParamDecl(ParamsTables(), &Params::payload_mass_kg);
  ExpectError(std::string(kMinimal) + "world:\n  payload_mass: " + ParamValueText(2 * m.max) +
                  "\n",
              {"world.payload_mass", ParamValueText(m.max)});
}

TEST(ScenarioTest, UnknownKeysAreNamedWithTheirPath) {
  ExpectError(std::string(kMinimal) + "colour: red\n", {"colour", "unknown key"});
  ExpectError(std::string(kMinimal) + "world:\n  payload_mas: 0.2\n",
              {"world.payload_mas", "unknown key"});
  ExpectError(std::string(kMinimal) +
                  "events:\n  - {at: 0.5, type: wind, force: [1, 0, 0], "
                  "duration: 1, gust: 2}\n",
              {"events.0.gust"});
}

TEST(ScenarioTest, WrongTypesAndRangesAreNamed) {
  ExpectError("name: t\nduration: long\n", {"duration", "expected a number"});
  ExpectError("name: t\nduration: -1\n", {"duration", "out of range"});
  ExpectError(std::string(kMinimal) + "controller: {type: pid}\n",
              {"controller.type", "hpa_mpc | nonhybrid_mpc | geometric"});
  ExpectError(std::string(kMinimal) + "reference: {type: hover, payload_position: [0, 0]}\n",
              {"reference.payload_position", "list of 3 numbers"});
  ExpectError(std::string(kMinimal) + "events:\n  - {at: 5.0, type: gripper_grab}\n",
              {"events.0.at", "after the end"});
  ExpectError(std::string(kMinimal) + "estimation: {ground_truth: maybe}\n",
              {"estimation.ground_truth", "true or false"});
  ExpectError("duration: 1.0\n", {"name", "missing"});
}

TEST(ScenarioTest, MissingAndMalformedFiles) {
  EXPECT_THROW(LoadScenario("/nonexistent.yaml"), InputError);
  ExpectError("name: [unclosed\n", {"malformed YAML"});
  ExpectError("- just\n- a list\n", {"map"});
}

}  // namespace
}  // namespace hpa

namespace hpa {
namespace {

TEST(WorldProfileTest, ScenarioFilesFlyTheFlightProfileUnlessTheySayIdeal) {
  const Scenario flight = LoadScenario(Write("flight.yaml", kMinimal));
  EXPECT_EQ(flight.world.name, "flight");
  EXPECT_TRUE(flight.world.contact.enabled);
  EXPECT_GT(flight.world.latency.compute_s, 0.0);
  const Scenario ideal = LoadScenario(Write("ideal.yaml", kMinimal), {{"world.profile", "ideal"}});
  EXPECT_EQ(ideal.world.name, "ideal");
  EXPECT_FALSE(ideal.world.contact.enabled);
  EXPECT_FALSE(ideal.world.mismatch.enabled);
  EXPECT_EQ(ideal.world.latency.compute_s, 0.0);
  // a scenario built in code is the ideal world
  EXPECT_EQ(Scenario().world.name, "ideal");
}

TEST(WorldProfileTest, ASingleNumberOverridesTheProfile) {
  const Scenario s =
      LoadScenario(Write("override.yaml", kMinimal), {{"world.latency.compute_s", "0.02"}});
  EXPECT_EQ(s.world.name, "flight");
  EXPECT_DOUBLE_EQ(s.world.latency.compute_s, 0.02);
  // the rest of the profile is kept
  EXPECT_GT(s.world.latency.transport_s, 0.0);
  EXPECT_TRUE(s.world.contact.enabled);
}

TEST(WorldProfileTest, BadProfilesAndKeysAreNamed) {
  ExpectError(std::string(kMinimal) + "world: {profile: windy}\n", {"world.profile", "windy"});
  ExpectError(std::string(kMinimal) + "world: {latency: {compute: 0.01}}\n",
              {"world.latency.compute"});
  ExpectError(std::string(kMinimal) + "world: {latency: {compute_s: 5}}\n",
              {"world.latency.compute_s"});
  ExpectError(std::string(kMinimal) + "world: {contact: {enabled: maybe}}\n",
              {"world.contact.enabled"});
}

TEST(WorldProfileTest, TheFlightProfileFliesPx4sRateLoopWithPx4sDefaults) {
  const Scenario flight = LoadScenario(Write("flight.yaml", kMinimal));
  const RateLoopSpec& r = flight.rate_loop;
  EXPECT_TRUE(r.px4);
  EXPECT_EQ(r.params.rate_hz, 1000.0);
  EXPECT_EQ(r.params.p, Eigen::Vector3d(0.15, 0.15, 0.2));
  EXPECT_EQ(r.params.i, Eigen::Vector3d(0.2, 0.2, 0.1));
  EXPECT_EQ(r.params.d, Eigen::Vector3d(0.003, 0.003, 0.0));
  EXPECT_EQ(r.params.integrator_limit, Eigen::Vector3d(0.3, 0.3, 0.3));
  EXPECT_EQ(r.params.gyro_cutoff_hz, 30.0);
  EXPECT_EQ(r.params.dgyro_cutoff_hz, 30.0);
  EXPECT_EQ(r.params.yaw_torque_cutoff_hz, 2.0);
  // the vehicle's rate gyro follows the loop
  EXPECT_TRUE(flight.world.rate_gyro.enabled);
  EXPECT_EQ(flight.world.rate_gyro.rate_hz, 1000.0);
  // the ideal world keeps the project's own loop, and has no rate gyro
  const Scenario ideal = LoadScenario(Write("ideal.yaml", kMinimal), {{"world.profile", "ideal"}});
  EXPECT_FALSE(ideal.rate_loop.px4);
  EXPECT_FALSE(ideal.world.rate_gyro.enabled);
  // one number overridden, the rest kept
  const Scenario s =
      LoadScenario(Write("override.yaml", kMinimal), {{"world.rate_loop.gyro_cutoff_hz", "80"}});
  EXPECT_EQ(s.rate_loop.params.gyro_cutoff_hz, 80.0);
  EXPECT_EQ(s.rate_loop.params.dgyro_cutoff_hz, 30.0);
  const Scenario half =
      LoadScenario(Write("half.yaml", kMinimal), {{"world.rate_loop.rate_hz", "500"}});
  EXPECT_EQ(half.world.rate_gyro.rate_hz, 500.0);
}

TEST(WorldProfileTest, BadRateLoopKeysAndValuesAreNamed) {
  const std::string w = std::string(kMinimal) + "world: {rate_loop: ";
  ExpectError(w + "{px4: true, gain: 1}}\n", {"world.rate_loop.gain"});
  ExpectError(w + "{rate_hz: 2000}}\n", {"world.rate_loop.rate_hz"});
  ExpectError(w + "{rate_hz: 300}}\n", {"world.rate_loop.rate_hz", "divides"});
  ExpectError(w + "{p: [0.15, 0.15]}}\n", {"world.rate_loop.p"});
  ExpectError(w + "{p: [0.15, 0.15, 0.9]}}\n", {"world.rate_loop.p"});
  ExpectError(w + "{integrator_limit: [0.3, -0.1, 0.3]}}\n", {"world.rate_loop.integrator_limit"});
  ExpectError(w + "{yaw_torque_cutoff_hz: 50}}\n", {"world.rate_loop.yaw_torque_cutoff_hz"});
  ExpectError(w + "{px4: yes please}}\n", {"world.rate_loop.px4"});
}

}  // namespace
}  // namespace hpa

namespace hpa {
namespace {

TEST(WorldProfileTest, AWindEventIsAForceOrAVelocityNotBoth) {
  const std::string base = std::string(kMinimal) + "events:\n  - {at: 0.5, type: wind, ";
  ExpectError(base + "force: [1, 0, 0], velocity: [3, 0, 0], duration: 1}\n", {"events.0"});
  ExpectError(base + "duration: 1}\n", {"events.0"});
  const Scenario s =
      LoadScenario(Write("wind_velocity.yaml", base + "velocity: [3, 0, 0], duration: 1}\n"));
  ASSERT_EQ(s.events.size(), 1u);
  const auto& wind = dynamic_cast<const WindEvent&>(*s.events[0].action);
  ASSERT_TRUE(wind.velocity_W_mps.has_value());
  EXPECT_EQ(wind.velocity_W_mps->x(), 3.0);
}

}  // namespace
}  // namespace hpa

namespace hpa {
namespace {

// Payload reference positions of a scenario's reference over one period after the ramp.
std::vector<Eigen::Vector3d> OnePeriod(const std::string& reference_yaml, double period_s) {
  const Scenario s =
      LoadScenario(Write("shape.yaml", std::string(kMinimal) + "reference: " + reference_yaml));
  const std::shared_ptr<Reference> ref = MakeReference(s, Params());
  std::vector<Eigen::Vector3d> points;
  for (int k = 0; k < 200; ++k) points.push_back(ref->At(10.0 + k * period_s / 200).p_WL_W);
  return points;
}

TEST(ReferenceShapesTest, ACircleKeepsItsRadiusAndHeight) {
  const auto points = OnePeriod(
      "{type: circle, radius: 1.5, period: 4, height: 1.2, centre: [1, -1, 0], ramp: 2}\n", 4.0);
  double min_x = 1e9, max_x = -1e9;
  for (const Eigen::Vector3d& p : points) {
    EXPECT_NEAR(std::hypot(p.x() - 1.0, p.y() + 1.0), 1.5, 1e-9);
    EXPECT_NEAR(p.z(), 1.2, 1e-12);
    min_x = std::min(min_x, p.x());
    max_x = std::max(max_x, p.x());
  }
  EXPECT_NEAR(max_x - min_x, 3.0, 1e-3);  // the whole circle in one period
}

TEST(ReferenceShapesTest, AFigureEightCrossesItsCentreTwicePerPeriod) {
  const auto points =
      OnePeriod("{type: figure_eight, half_length: 2, half_width: 0.5, period: 6}\n", 6.0);
  int crossings = 0;
  for (size_t k = 1; k < points.size(); ++k) {
    if ((points[k - 1].x() < 0) != (points[k].x() < 0)) ++crossings;
    EXPECT_LE(std::abs(points[k].x()), 2.0 + 1e-9);
    EXPECT_LE(std::abs(points[k].y()), 0.5 + 1e-9);
    // on the lemniscate y = b sin(2 theta) with x = a sin(theta): y^2 = 4 b^2 (x/a)^2 (1 - (x/a)^2)
    const double u = points[k].x() / 2.0;
    EXPECT_NEAR(points[k].y() * points[k].y(), 4 * 0.25 * u * u * (1 - u * u), 1e-9);
  }
  EXPECT_EQ(crossings, 2);
}

TEST(ReferenceShapesTest, MissingOrBadShapeKeysAreNamed) {
  ExpectError(std::string(kMinimal) + "reference: {type: circle, period: 4}\n",
              {"reference.radius"});
  ExpectError(std::string(kMinimal) + "reference: {type: figure_eight, half_length: 2}\n",
              {"reference.half_width"});
  ExpectError(std::string(kMinimal) + "reference: {type: circle, radius: -1}\n",
              {"reference.radius"});
  ExpectError(std::string(kMinimal) + "reference: {type: circle, radius: 1, a: 2}\n",
              {"reference.a", "unknown key"});
}

}  // namespace
}  // namespace hpa
