#include "hpa/models/params.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "hpa/models/input_error.h"
#include "models/tests/temp_dir.h"

namespace hpa {
namespace {

std::string WriteTemp(const std::string& text) {
  const std::string path = TestTempDir() + "params_test.yaml";
  std::ofstream(path) << text;
  return path;
}

std::string ReadDefault() {
  std::ifstream in(DefaultParamsPath());
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(ParamsTest, DefaultFileLoadsThePaperValues) {
  const Params p = LoadParams(DefaultParamsPath());
  EXPECT_DOUBLE_EQ(p.quad_mass_kg, 0.72);
  EXPECT_DOUBLE_EQ(p.payload_mass_kg, 0.1);
  EXPECT_DOUBLE_EQ(p.cable_length_m, 0.5);
  EXPECT_DOUBLE_EQ(p.gravity_mps2, 9.81);
  EXPECT_EQ(p.camera_width_px, 1280);
  EXPECT_EQ(p.camera_height_px, 720);
  // thrust-to-weight of quadrotor + payload about 2.5 (docs/design.md section 2)
  const double max_thrust_N = 4 * p.k_f_N_per_radps2 * std::pow(p.motor_speed_max_radps, 2);
  EXPECT_NEAR(max_thrust_N / p.HoverThrustN(), 2.5, 0.05);
}

// Unit tests that build `Params{}` rely on the struct's defaults being params.yaml's numbers.
TEST(ParamsTest, StructDefaultsEqualTheFile) {
  const Params d;
  const Params f = LoadParams(DefaultParamsPath());
  EXPECT_EQ(d.gravity_mps2, f.gravity_mps2);
  EXPECT_EQ(d.quad_mass_kg, f.quad_mass_kg);
  EXPECT_EQ(d.inertia_B_kgm2, f.inertia_B_kgm2);
  EXPECT_EQ(d.arm_length_m, f.arm_length_m);
  EXPECT_EQ(d.body_half_size_m, f.body_half_size_m);
  EXPECT_EQ(d.k_f_N_per_radps2, f.k_f_N_per_radps2);
  EXPECT_EQ(d.k_m_Nm_per_radps2, f.k_m_Nm_per_radps2);
  EXPECT_EQ(d.motor_time_constant_s, f.motor_time_constant_s);
  EXPECT_EQ(d.motor_speed_min_radps, f.motor_speed_min_radps);
  EXPECT_EQ(d.motor_speed_max_radps, f.motor_speed_max_radps);
  EXPECT_EQ(d.payload_mass_kg, f.payload_mass_kg);
  EXPECT_EQ(d.payload_radius_m, f.payload_radius_m);
  EXPECT_EQ(d.cable_length_m, f.cable_length_m);
  EXPECT_EQ(d.slack_epsilon_m, f.slack_epsilon_m);
  EXPECT_EQ(d.camera_width_px, f.camera_width_px);
  EXPECT_EQ(d.camera_height_px, f.camera_height_px);
  EXPECT_EQ(d.camera_fovy_deg, f.camera_fovy_deg);
  EXPECT_EQ(d.t_BC_B_m, f.t_BC_B_m);
  EXPECT_EQ(d.R_BC, f.R_BC);
  EXPECT_EQ(d.vio_width_px, f.vio_width_px);
  EXPECT_EQ(d.vio_height_px, f.vio_height_px);
}

TEST(ParamsTest, UnknownKeyIsNamed) {
  std::string text = ReadDefault();
  text.replace(text.find("payload:"), 8, "payload:\n  colour: red");
  try {
    LoadParams(WriteTemp(text));
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("payload.colour"), std::string::npos) << e.what();
  }
}

TEST(ParamsTest, OutOfRangeValueIsNamed) {
  std::string text = ReadDefault();
  text.replace(text.find("mass_kg: 0.1 "), 12, "mass_kg: -1 ");
  try {
    LoadParams(WriteTemp(text));
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("payload.mass_kg"), std::string::npos) << e.what();
  }
}

TEST(ParamsTest, MissingAndMalformedFiles) {
  EXPECT_THROW(LoadParams("/nonexistent/params.yaml"), InputError);
  EXPECT_THROW(LoadParams(WriteTemp("quadrotor: [1, 2")), InputError);
}

}  // namespace
}  // namespace hpa
