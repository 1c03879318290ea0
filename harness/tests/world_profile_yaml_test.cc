// World profiles: the shipped names, loading models/profiles/<name>.yaml, a scenario's section
// overrides (absent keys kept, unknown keys and bad rates refused) and the Markdown table.

#include "hpa/scenarios/world_profile_yaml.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "hpa/models/input_error.h"
#include "hpa/models/yaml_reader.h"

namespace hpa {
namespace {

YamlMap MapOf(const std::string& text) {
  return YamlMap(LoadYamlText(text, "world.yaml"), "world.yaml", "world");
}

TEST(WorldProfileYamlTest, ShippedProfilesAreIdealAndFlight) {
  EXPECT_EQ(WorldProfileNames(), (std::vector<std::string>{"ideal", "flight"}));
}

TEST(WorldProfileYamlTest, FlightProfileLoadsTheFilesNumbers) {
  const WorldProfileSpec flight = LoadWorldProfile("flight");
  EXPECT_EQ(flight.world.name, "flight");
  // values copied from models/profiles/flight.yaml (exact: decimal text to double both ways)
  EXPECT_EQ(flight.world.latency.compute_s, 0.00667);
  EXPECT_EQ(flight.world.latency.estimate_s, 0.002);
  EXPECT_EQ(flight.world.camera.exposure_s, 0.005);
  EXPECT_TRUE(flight.world.contact.enabled);
  EXPECT_TRUE(flight.world.mismatch.enabled);
  // PX4's loop flown, so the vehicle has its rate gyro at the loop's rate
  EXPECT_TRUE(flight.rate_loop.px4);
  EXPECT_TRUE(flight.world.rate_gyro.enabled);
  EXPECT_EQ(flight.world.rate_gyro.rate_hz, flight.rate_loop.params.rate_hz);
}

TEST(WorldProfileYamlTest, IdealProfileTurnsTheRealismOff) {
  const WorldProfileSpec ideal = LoadWorldProfile("ideal");
  EXPECT_EQ(ideal.world.name, "ideal");
  EXPECT_FALSE(ideal.world.contact.enabled);
  EXPECT_FALSE(ideal.world.mismatch.enabled);
  EXPECT_EQ(ideal.world.latency.compute_s, 0.0);
  EXPECT_FALSE(ideal.rate_loop.px4);
  EXPECT_FALSE(ideal.world.rate_gyro.enabled);
}

TEST(WorldProfileYamlTest, UnknownProfileIsRefusedByName) {
  try {
    LoadWorldProfile("stormy");
    FAIL() << "an unknown profile was loaded";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "world.profile");
    EXPECT_NE(std::string(e.what()).find("stormy"), std::string::npos) << e.what();
  }
}

TEST(WorldProfileYamlTest, OverrideChangesOnlyTheKeysGiven) {
  WorldProfileSpec spec = LoadWorldProfile("flight");
  const WorldProfileSpec base = spec;
  ReadWorldProfileSections(MapOf("{latency: {compute_s: 0.0}, wind: {mean_x_mps: 3.5}}"), &spec);
  EXPECT_EQ(spec.world.latency.compute_s, 0.0);
  EXPECT_EQ(spec.world.wind.mean_x_mps, 3.5);
  // the other keys of the same sections, and the sections not named, keep their values
  EXPECT_EQ(spec.world.latency.estimate_s, base.world.latency.estimate_s);
  EXPECT_EQ(spec.world.latency.transport_s, base.world.latency.transport_s);
  EXPECT_EQ(spec.world.wind.gust_length_m, base.world.wind.gust_length_m);
  EXPECT_EQ(spec.world.camera.exposure_s, base.world.camera.exposure_s);
  EXPECT_EQ(spec.rate_loop.px4, base.rate_loop.px4);
}

TEST(WorldProfileYamlTest, SwitchingToPx4GivesTheVehicleItsGyro) {
  WorldProfileSpec spec = LoadWorldProfile("ideal");
  ReadWorldProfileSections(MapOf("{rate_loop: {px4: true, rate_hz: 500.0}}"), &spec);
  EXPECT_TRUE(spec.rate_loop.px4);
  EXPECT_EQ(spec.rate_loop.params.rate_hz, 500.0);
  EXPECT_TRUE(spec.world.rate_gyro.enabled);
  EXPECT_EQ(spec.world.rate_gyro.rate_hz, 500.0);
}

TEST(WorldProfileYamlTest, UnknownKeyInASectionIsRefusedWithTheValidOnes) {
  WorldProfileSpec spec;
  try {
    ReadWorldProfileSections(MapOf("{latency: {compute_ms: 5}}"), &spec);
    FAIL() << "an unknown key was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("compute_ms"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("compute_s"), std::string::npos) << e.what();
  }
}

TEST(WorldProfileYamlTest, RateLoopRateMustDivideThePhysicsRate) {
  WorldProfileSpec spec;
  // 1000 / 300 is not a whole number of physics steps
  EXPECT_THROW(ReadWorldProfileSections(MapOf("{rate_loop: {rate_hz: 300.0}}"), &spec), InputError);
  EXPECT_NO_THROW(ReadWorldProfileSections(MapOf("{rate_loop: {rate_hz: 250.0}}"), &spec));
  EXPECT_EQ(spec.rate_loop.params.rate_hz, 250.0);
}

TEST(WorldProfileYamlTest, OneMotionBlurSubframeIsRefused) {
  WorldProfileSpec spec;
  EXPECT_THROW(ReadWorldProfileSections(MapOf("{camera: {motion_blur_subframes: 1}}"), &spec),
               InputError);
  EXPECT_NO_THROW(ReadWorldProfileSections(MapOf("{camera: {motion_blur_subframes: 2}}"), &spec));
  EXPECT_EQ(spec.world.camera.motion_blur_subframes, 2);
}

TEST(WorldProfileYamlTest, MarkdownListsEverySectionWithTheProfilesName) {
  const std::string md = WorldProfileMarkdown("flight");
  for (const char* section : {"contact", "actuation", "latency", "mismatch", "aero", "wind", "vio",
                              "imu", "camera", "rate_loop"}) {
    EXPECT_NE(md.find(std::string("### `world.") + section + "`"), std::string::npos) << section;
  }
  EXPECT_NE(md.find("`flight`"), std::string::npos);
  EXPECT_NE(md.find("px4: true"), std::string::npos);  // the flight profile flies PX4's loop
  EXPECT_NE(md.find("compute_s"), std::string::npos);
}

}  // namespace
}  // namespace hpa
