#include "hpa/models/params_yaml.h"

#include <gtest/gtest.h>

#include "hpa/models/input_error.h"

namespace hpa {
namespace {

// No override gives back every bit of the base (doubles survive the YAML text).
TEST(ParamsYamlTest, NoOverrideGivesTheBaseBitForBit) {
  const Params base = LoadParams(DefaultParamsPath());
  const Params same = ParamsWithOverrides(base, YAML::Node(YAML::NodeType::Map), "s.yaml");
  EXPECT_EQ(same.k_f_N_per_radps2, base.k_f_N_per_radps2);
  EXPECT_EQ(same.inertia_B_kgm2, base.inertia_B_kgm2);
  EXPECT_EQ(same.camera_distortion, base.camera_distortion);
  EXPECT_EQ(same.R_BC, base.R_BC);
  EXPECT_EQ(same.cable_length_m, base.cable_length_m);
  EXPECT_EQ(same.camera_width_px, base.camera_width_px);
}

TEST(ParamsYamlTest, AnOverrideChangesOnlyItsValue) {
  const Params base = LoadParams(DefaultParamsPath());
  const Params p = ParamsWithOverrides(
      base, YAML::Load("{cable: {length_m: 0.8}, payload: {mass_kg: 0.25}}"), "s.yaml");
  EXPECT_EQ(p.cable_length_m, 0.8);
  EXPECT_EQ(p.payload_mass_kg, 0.25);
  EXPECT_EQ(p.slack_epsilon_m, base.slack_epsilon_m);
  EXPECT_EQ(p.quad_mass_kg, base.quad_mass_kg);
}

// Errors name the scenario file and the key as params.SECTION.KEY, with params.yaml's ranges.
TEST(ParamsYamlTest, BadOverridesAreNamed) {
  const Params base;
  const auto message = [&](const std::string& yaml) {
    try {
      ParamsWithOverrides(base, YAML::Load(yaml), "scen.yaml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const std::string range = message("{cable: {length_m: 30}}");
  EXPECT_NE(range.find("scen.yaml"), std::string::npos) << range;
  EXPECT_NE(range.find("params.cable.length_m"), std::string::npos) << range;
  EXPECT_NE(range.find("[0.05, 10]"), std::string::npos) << range;
  const std::string unknown = message("{cable: {lenght_m: 0.8}}");
  EXPECT_NE(unknown.find("valid keys here: length_m, slack_epsilon_m"), std::string::npos)
      << unknown;
  EXPECT_NE(message("[1, 2]").find("expected a map"), std::string::npos);
  EXPECT_NE(message("{rotor: {motor_speed_max_radps: 50}}").find("motor_speed_min_radps"),
            std::string::npos);
}

}  // namespace
}  // namespace hpa
