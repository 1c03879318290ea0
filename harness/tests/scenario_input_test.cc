// Scenario files written by a careless or hostile hand are refused with the key named.

#include <gtest/gtest.h>

#include <fstream>

#include "hpa/models/input_error.h"
#include "hpa/scenarios/scenario.h"
#include "models/tests/temp_dir.h"

namespace hpa {
namespace {

// The InputError message of loading `text` as a scenario, or "" if it loads.
std::string LoadError(const std::string& text) {
  const std::string path = TestTempDir() + "scenario.yaml";
  std::ofstream(path) << text;
  try {
    LoadScenario(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(ScenarioInputTest, NameMustBeASafeFolderName) {
  for (const char* name : {"../../x", "a/b", ".hidden", "", "with space", "semi;colon"}) {
    const std::string error = LoadError(std::string("name: '") + name + "'\nduration: 1\n");
    EXPECT_NE(error.find("'name'"), std::string::npos) << name << ": " << error;
  }
  EXPECT_EQ(LoadError("name: hover_T5-a.1\nduration: 1\n"), "");
}

TEST(ScenarioInputTest, DurationIsCappedAtAnHour) {
  EXPECT_NE(LoadError("name: x\nduration: 3600.5\n").find("'duration'"), std::string::npos);
  EXPECT_EQ(LoadError("name: x\nduration: 3600\n"), "");
}

TEST(ScenarioInputTest, QuotedNumbersAndBooleansAreRefused) {
  EXPECT_NE(LoadError("name: x\nduration: 1\nseed: \"5\"\n").find("quoted"), std::string::npos);
  EXPECT_NE(
      LoadError("name: x\nduration: 1\nestimation: {ground_truth: \"true\"}\n").find("quoted"),
      std::string::npos);
}

TEST(ScenarioInputTest, DuplicateAndComplexKeysAreRefused) {
  EXPECT_NE(LoadError("name: x\nduration: 1\nduration: 2\n").find("duplicate"), std::string::npos);
  EXPECT_NE(LoadError("name: x\nduration: 1\n? [a]\n: 1\n").find("plain name"), std::string::npos);
}

TEST(ScenarioInputTest, QpMethodIsOneOfTheRtiMethods) {
  const std::string path = TestTempDir() + "q.yaml";
  std::ofstream(path) << "name: x\nduration: 1\n";
  EXPECT_EQ(LoadScenario(path).controller.Name("qp_method"), "structured");
  std::ofstream(path) << "name: x\nduration: 1\ncontroller: {qp_method: riccati}\n";
  EXPECT_EQ(LoadScenario(path).controller.Name("qp_method"), "riccati");
  const std::string error = LoadError("name: x\nduration: 1\ncontroller: {qp_method: hpipm}\n");
  EXPECT_NE(error.find("controller.qp_method"), std::string::npos) << error;
  EXPECT_NE(error.find("dense"), std::string::npos) << error;
}

TEST(ScenarioInputTest, EstimatorVariantComesFromTheRegistryOrTheController) {
  const std::string path = TestTempDir() + "e.yaml";
  std::ofstream(path) << "name: x\nduration: 1\ncontroller: {type: nonhybrid_mpc}\n";
  EXPECT_EQ(EstimatorOf(LoadScenario(path)), "always_taut");
  std::ofstream(path) << "name: x\nduration: 1\ncontroller: {type: nonhybrid_mpc}\n"
                         "estimation: {estimator: always_taut_projected}\n";
  EXPECT_EQ(EstimatorOf(LoadScenario(path)), "always_taut_projected");
  const std::string error = LoadError("name: x\nduration: 1\nestimation: {estimator: ukf}\n");
  EXPECT_NE(error.find("estimation.estimator"), std::string::npos) << error;
  EXPECT_NE(error.find("always_taut_projected"), std::string::npos) << error;
}

}  // namespace
}  // namespace hpa
