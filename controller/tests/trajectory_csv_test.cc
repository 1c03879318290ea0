// The reference CSV reader: refusals name the file, line and column; derivatives and
// interpolation; the bounds on what a file may say or imply (positions, time steps, speeds, the
// quadrotor reference); files that are not regular files are refused without being read.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <fstream>

#include "hpa/controller/reference.h"
#include "hpa/controller/reference_types.h"
#include "hpa/models/input_error.h"
#include "models/tests/temp_dir.h"

namespace hpa {
namespace {

// The position bound every reference shares (reference_types.h), as the csv type passes it.
constexpr PositionRange kRange{-kReferencePositionBound_m, kReferencePositionBound_m};

std::string Write(const std::string& text) {
  const std::string path = TestTempDir() + "reference.csv";
  std::ofstream(path) << text;
  return path;
}

// Loads `text` expecting an InputError whose message holds `fragment`.
void ExpectError(const std::string& text, const std::string& fragment) {
  try {
    LoadTrajectoryCsv(Write(text), kRange);
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

// Rows 1e-300 s apart differentiate to an infinite acceleration (the quadrotor reference was
// -nan in log.csv): refused by the minimum step, naming the row.
TEST(TrajectoryCsvTest, RowsCloserThanTheMinimumStepAreRefused) {
  ExpectError("t_s,x_m,y_m,z_m\n0,0,0,0.8\n1e-300,1,0,0.8\n0.2,1,0,0.8\n", "line 3 column 1");
  ExpectError("t_s,x_m,y_m,z_m\n0,0,0,0.8\n1e-300,1,0,0.8\n0.2,1,0,0.8\n",
              "at least 0.0001 s apart");
  // exactly the minimum step is fine (0.5 mm in 0.1 ms: 5 m/s)
  EXPECT_NO_THROW(
      LoadTrajectoryCsv(Write("t_s,x_m,y_m,z_m\n0,0,0,0.8\n0.0001,0.0005,0,0.8\n"), kRange));
}

// Positions are bounded as the hover reference's are, speeds by kMaxTrajectorySpeed_mps, given
// or derived; the message names the line.
TEST(TrajectoryCsvTest, PositionsAndSpeedsAreBounded) {
  ExpectError("t_s,x_m,y_m,z_m\n0,0,0,1\n1,1e300,0,1\n", "line 3 column 2");
  ExpectError("t_s,x_m,y_m,z_m\n0,0,0,1\n1,0,-1000.5,1\n", "outside the reference positions");
  // 1e9 m/s given
  ExpectError("t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps\n0,0,0,1,1e9,0,0\n1,1,0,1,0,0,0\n", "line 2");
  ExpectError("t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps\n0,0,0,1,1e9,0,0\n1,1,0,1,0,0,0\n",
              "faster than the vehicle can fly");
  // 100 m in 1 s, derived from the positions: 100 m/s at both rows
  ExpectError("t_s,x_m,y_m,z_m\n0,0,0,1\n1,100,0,1\n", "differenced between lines 2 and 3");
  // the bound itself is accepted (39 m in 1 s)
  EXPECT_NO_THROW(LoadTrajectoryCsv(Write("t_s,x_m,y_m,z_m\n0,0,0,1\n1,39,0,1\n"), kRange));
}

// A spreadsheet's UTF-8 byte order mark before the header is not part of the column name.
TEST(TrajectoryCsvTest, AByteOrderMarkIsSkipped) {
  const std::vector<TrajectorySample> s =
      LoadTrajectoryCsv(Write("\xEF\xBB\xBFt_s,x_m,y_m,z_m\n0,0,0,1\n1,1,0,1\n"), kRange);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[1].p_WL_W.x(), 1.0);
  EXPECT_EQ(s[1].line, 3);
}

// A folder, /dev/zero and a FIFO are refused at once as "not a regular file" (a FIFO with no
// writer would block a reader forever, /dev/zero never ends).
TEST(TrajectoryCsvTest, NotARegularFileIsRefusedWithoutReading) {
  const std::string dir = TestTempDir();
  const std::string fifo = dir + "fifo.csv";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  for (const std::string& path : {dir, std::string("/dev/zero"), fifo}) {
    const auto start = std::chrono::steady_clock::now();
    try {
      LoadTrajectoryCsv(path, kRange);
      FAIL() << path << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
    // refused before any read: far below the 20 s /dev/zero took when it was read
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 1.0);
  }
}

// The quadrotor reference is checked with the params that build it: an acceleration at free
// fall leaves the cable's direction undefined, and every value at every sample must be finite.
TEST(TrajectoryCsvTest, TheQuadrotorReferenceIsCheckedByLine) {
  const Params params;
  const std::string header = "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,ax_mps2,ay_mps2,az_mps2\n";
  const std::vector<TrajectorySample> free_fall =
      LoadTrajectoryCsv(Write(header + "0,0,0,1,0,0,0,0,0,0\n1,0,0,1,0,0,0,0,0,-9.81\n"), kRange);
  try {
    CheckSampledReference(params, free_fall, "reference.csv");
    FAIL() << "a free-fall acceleration was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("free fall"), std::string::npos) << e.what();
  }
  // a jerk that overflows: 1e305 m/s^2 to -1e305 m/s^2 in 0.1 ms
  const std::vector<TrajectorySample> overflow = LoadTrajectoryCsv(
      Write(header + "0,0,0,1,0,0,0,0,0,1e305\n0.0001,0,0,1,0,0,0,0,0,-1e305\n"), kRange);
  EXPECT_THROW(CheckSampledReference(params, overflow, "reference.csv"), InputError);
  // the rows with a sane step: every value finite, accepted
  const std::vector<TrajectorySample> fine = LoadTrajectoryCsv(
      Write("t_s,x_m,y_m,z_m\n0,0,0,0.8\n0.1,0.1,0,0.8\n0.2,0.2,0,0.8\n"), kRange);
  EXPECT_NO_THROW(CheckSampledReference(params, fine, "reference.csv"));
}

// Positions of x = t^2 (acceleration 2): central differences give v = 2t exactly inside, and
// the reference interpolates between samples.
TEST(TrajectoryCsvTest, DifferentiatesAndInterpolates) {
  std::string text = "# a comment\nt_s, x_m, y_m, z_m\n";
  for (int i = 0; i <= 10; ++i) {
    const double t = 0.1 * i;
    text += std::to_string(t) + "," + std::to_string(t * t) + ",0,1\n";
  }
  const std::vector<TrajectorySample> s = LoadTrajectoryCsv(Write(text), kRange);
  ASSERT_EQ(s.size(), 11u);
  EXPECT_NEAR(s[5].v_WL_W.x(), 1.0, 1e-9);  // 2 t at t = 0.5
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
