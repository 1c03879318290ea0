// DataDir/DataPath: $HPA_DATA_DIR honoured when it holds models/params.yaml, refused (naming the
// folder) when it does not, and the build tree's source tree when it is unset or empty.

#include "hpa/models/data_dir.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdlib>
#include <fstream>
#include <optional>
#include <string>

#include "hpa/models/input_error.h"
#include "temp_dir.h"

namespace hpa {
namespace {

// Saves $HPA_DATA_DIR before each test and puts it back after, so the cases do not leak into
// each other when the binary runs them all in one process.
class DataDirTest : public testing::Test {
 protected:
  void SetUp() override {
    if (const char* env = std::getenv("HPA_DATA_DIR")) saved_ = env;
  }
  void TearDown() override {
    if (saved_) {
      setenv("HPA_DATA_DIR", saved_->c_str(), 1);
    } else {
      unsetenv("HPA_DATA_DIR");
    }
  }

  // A fresh data folder under the test's temp dir, holding models/params.yaml if `with_params`.
  static std::string MakeFolder(const std::string& name, bool with_params) {
    const std::string dir = TestTempDir() + name;
    mkdir(dir.c_str(), 0755);
    if (with_params) {
      mkdir((dir + "/models").c_str(), 0755);
      std::ofstream(dir + "/models/params.yaml") << "# stand-in: only its existence is checked\n";
    }
    return dir;
  }

 private:
  std::optional<std::string> saved_;
};

TEST_F(DataDirTest, ValidEnvFolderIsReturnedAsIs) {
  const std::string dir = MakeFolder("data", true);
  ASSERT_EQ(setenv("HPA_DATA_DIR", dir.c_str(), 1), 0);
  EXPECT_EQ(DataDir(), dir);
  EXPECT_EQ(DataPath("models/scene.xml"), dir + "/models/scene.xml");
}

TEST_F(DataDirTest, EnvFolderWithoutParamsIsRefusedByName) {
  const std::string dir = MakeFolder("empty", false);
  ASSERT_EQ(setenv("HPA_DATA_DIR", dir.c_str(), 1), 0);
  try {
    DataDir();
    FAIL() << "a folder without models/params.yaml was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), dir);
    EXPECT_EQ(e.key(), "HPA_DATA_DIR");
    EXPECT_NE(std::string(e.what()).find(dir), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("models/params.yaml"), std::string::npos) << e.what();
  }
  // DataPath goes through the same check
  EXPECT_THROW(DataPath("models/params.yaml"), InputError);
}

TEST_F(DataDirTest, MissingEnvFolderIsRefused) {
  const std::string dir = TestTempDir() + "does_not_exist";
  ASSERT_EQ(setenv("HPA_DATA_DIR", dir.c_str(), 1), 0);
  EXPECT_THROW(DataDir(), InputError);
}

// This test binary lives in the build tree, so with no override the data is the source tree it
// was built from (no share/hpa beside a build-tree program).
TEST_F(DataDirTest, UnsetEnvGivesTheSourceTreeOfTheBuild) {
  ASSERT_EQ(unsetenv("HPA_DATA_DIR"), 0);
  EXPECT_EQ(DataDir(), HPA_SOURCE_DIR);
  EXPECT_TRUE(std::ifstream(DataPath("models/params.yaml")).good()) << DataDir();
}

TEST_F(DataDirTest, EmptyEnvCountsAsUnset) {
  ASSERT_EQ(setenv("HPA_DATA_DIR", "", 1), 0);
  EXPECT_EQ(DataDir(), HPA_SOURCE_DIR);
}

}  // namespace
}  // namespace hpa
