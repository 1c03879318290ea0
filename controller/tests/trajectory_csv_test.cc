#include <gtest/gtest.h>

#include <fstream>

#include "hpa/controller/reference.h"
#include "hpa/models/input_error.h"
#include "models/tests/temp_dir.h"

namespace hpa {
namespace {

std::string Write(const std::string& text) {
  const std::string path = TestTempDir() + "reference.csv";
  std::ofstream(path) << text;
  return path;
}

// Loads `text` expecting an InputError whose message holds `fragment`.
void ExpectError(const std::string& text, const std::string& fragment) {
  try {
    LoadTrajectoryCsv(Write(text));
    FAIL() << "accepted:\n" << text;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("reference.csv"), std::string::npos) << e.what();
  }
}

TEST(TrajectoryCsvTest, BadFilesAreRefusedNamingLineAndColumn) {
  ExpectError("", "empty");
  ExpectError("t_s,x_m,y_m\n0,0,0\n1,0,0\n", "missing column 'z_m'");
  ExpectError("t_s,x_m,y_m,z_m,w_m\n", "unknown column 'w_m'");
  ExpectError("t_s,x_m,y_m,z_m\n0,0,0,1\n1,0,0\n", "'line 3': 3 values, the header has 4");
  ExpectError("t_s,x_m,y_m,z_m\n0,0,0,1\n1,nan,0,1\n", "line 3 column 2");
  ExpectError("t_s,x_m,y_m,z_m\n0,0,0,1\n1,abc,0,1\n", "'abc' is not a finite number");
  ExpectError("t_s,x_m,y_m,z_m\n0,0,0,1\n1,0,0,1\n1,0,0,1\n", "does not increase");
  ExpectError("t_s,x_m,y_m,z_m\n0,0,0,1\n", "at least two rows, found 1");
  ExpectError("t_s,x_m,y_m,z_m,vx_mps\n0,0,0,1,0\n1,0,0,1,0\n", "all of vx_mps, vy_mps, vz_mps");
}

// Positions of x = t^2 (acceleration 2): central differences give v = 2t exactly inside, and
// the reference interpolates between samples.
TEST(TrajectoryCsvTest, DifferentiatesAndInterpolates) {
  std::string text = "# a comment\nt_s, x_m, y_m, z_m\n";
  for (int i = 0; i <= 10; ++i) {
    const double t = 0.1 * i;
    text += std::to_string(t) + "," + std::to_string(t * t) + ",0,1\n";
  }
  const std::vector<TrajectorySample> s = LoadTrajectoryCsv(Write(text));
  ASSERT_EQ(s.size(), 11u);
  EXPECT_NEAR(s[5].v_WL_W.x(), 1.0, 1e-9);   // 2 t at t = 0.5
  EXPECT_NEAR(s[5].a_WL_W.x(), 2.0, 1e-6);
  const std::shared_ptr<Reference> r = MakeSampledReference(Params(), s);
  const ReferencePoint mid = r->At(0.55);
  EXPECT_NEAR(mid.p_WL_W.x(), 0.5 * (0.25 + 0.36), 1e-9);  // linear between samples
  EXPECT_NEAR(mid.v_WL_W.x(), 1.1, 1e-9);
  const ReferencePoint after = r->At(5.0);  // held at rest after the file
  EXPECT_NEAR(after.p_WL_W.x(), 1.0, 1e-9);
  EXPECT_EQ(after.v_WL_W.norm(), 0.0);
  EXPECT_NEAR(after.p_WQ_W.z() - after.p_WL_W.z(), Params().cable_length_m, 1e-12);
}

}  // namespace
}  // namespace hpa
