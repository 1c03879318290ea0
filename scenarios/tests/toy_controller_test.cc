// Extending by registration: a toy controller registered in a test flies a scenario through the
// real `hpa run` command line, and its name is valid everywhere the built-ins' are.

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hpa/controller/controller_registry.h"
#include "hpa/scenarios/cli.h"
#include "models/tests/temp_dir.h"

namespace hpa {
namespace {

// Hover thrust and zero body rates: enough to hold a hovering vehicle for a second.
class HoldController : public Controller {
 public:
  explicit HoldController(const Params& params) : thrust_N_(params.HoverThrustN()) {}
  ControlOutput Update(const SystemState&) override {
    ControlOutput out;
    out.command.thrust_N = thrust_N_;
    return out;
  }
  double RateHz() const override { return 100.0; }

 private:
  double thrust_N_;
};

int Hpa(std::vector<std::string> args) {
  args.insert(args.begin(), "hpa");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  return HpaMain(static_cast<int>(argv.size()), argv.data());
}

TEST(ToyControllerTest, RegisteredControllerRunsThroughHpaRun) {
  if (FindController("toy_hold") == nullptr) {
    // the one registration line a new controller needs
    RegisterController(
        {"toy_hold", "holds the hover thrust (test)", "hybrid",
         [](const ControllerConfig&, const Params& params, std::shared_ptr<const Reference>) {
           return std::make_unique<HoldController>(params);
         }});
  }
  const std::string dir = TestTempDir();
  std::ofstream(dir + "toy.yaml")
      << "name: toy\nduration: 1.0\nworld: {profile: ideal}\n"
         "controller: {type: toy_hold}\n"
         "estimation: {ground_truth: true, camera: analytic}\n"
         "reference: {type: hover, payload_position: [0, 0, 0.7]}\n"
         "expect: {crashed: false, quad_position_deviation_max: 0.05}\n";
  ASSERT_EQ(Hpa({"run", dir + "toy.yaml", "--out", dir + "out", "--quiet"}), 0);
  std::ifstream in(dir + "out/metrics.json");
  const nlohmann::json metrics = nlohmann::json::parse(in);
  EXPECT_EQ(metrics["controller"], "toy_hold");
  EXPECT_FALSE(metrics["crashed"].get<bool>());
  // the --controller override takes the registered name too; an unknown one is bad input
  EXPECT_EQ(
      Hpa({"run", dir + "toy.yaml", "--controller", "toy_hold", "--out", dir + "out2", "--quiet"}),
      0);
  EXPECT_EQ(Hpa({"run", dir + "toy.yaml", "--controller", "toy_nope", "--quiet"}), 2);
}

}  // namespace
}  // namespace hpa
