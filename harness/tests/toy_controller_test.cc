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
  explicit HoldController(const Params& params, double thrust_scale = 1.0)
      : thrust_N_(thrust_scale * params.HoverThrustN()) {}
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

// A controller's own setting is one declaration in its registration: the scenario's controller
// block and --set take it, its range is checked naming the key, `hpa schema` lists it, and a key
// no controller declares is refused naming the declared ones.
TEST(ToyControllerTest, AControllersOwnSettingIsDeclaredWithIt) {
  if (FindController("toy_scaled") == nullptr) {
    RegisterController(
        {"toy_scaled", "hover thrust times its own setting (test)", "hybrid",
         [](const ControllerConfig& config, const Params& params,
            std::shared_ptr<const Reference>) {
           return std::make_unique<HoldController>(params, config.Number("thrust_scale"));
         },
         {{"thrust_scale", "-", 1.0, 0.5, 1.5, nullptr, "times the hover thrust"}}});
  }
  const std::string dir = TestTempDir();
  std::ofstream(dir + "scaled.yaml")
      << "name: scaled\nduration: 1.0\nworld: {profile: ideal}\n"
         "controller: {type: toy_scaled, thrust_scale: 1.0}\n"
         "estimation: {ground_truth: true, camera: analytic}\n"
         "reference: {type: hover, payload_position: [0, 0, 0.7]}\n";
  const auto deviation_m = [&](const std::string& out, std::vector<std::string> sets) {
    std::vector<std::string> args{"run", dir + "scaled.yaml", "--out", dir + out, "--quiet"};
    for (const std::string& s : sets) args.insert(args.end(), {"--set", s});
    EXPECT_EQ(Hpa(args), 0) << out;
    std::ifstream in(dir + out + "/metrics.json");
    return nlohmann::json::parse(in)["quad_position_deviation_max_m"].get<double>();
  };
  // as declared, the vehicle holds; at 1.2 times the hover thrust it climbs away
  EXPECT_LT(deviation_m("held", {}), 0.05);
  EXPECT_GT(deviation_m("climbs", {"controller.thrust_scale=1.2"}), 0.5);
  EXPECT_EQ(Hpa({"run", dir + "scaled.yaml", "--set", "controller.thrust_scale=2", "--quiet"}), 2);
  std::ofstream(dir + "typo.yaml") << "name: typo\nduration: 1.0\n"
                                      "controller: {type: toy_scaled, thrust_scael: 1.0}\n";
  testing::internal::CaptureStderr();
  EXPECT_EQ(Hpa({"run", dir + "typo.yaml", "--quiet"}), 2);
  const std::string error = testing::internal::GetCapturedStderr();
  EXPECT_NE(error.find("thrust_scael"), std::string::npos) << error;
  EXPECT_NE(error.find("thrust_scale,"), std::string::npos) << error;
  testing::internal::CaptureStdout();
  Hpa({"schema", "controller"});
  const std::string schema = testing::internal::GetCapturedStdout();
  EXPECT_NE(schema.find("`controller.thrust_scale` | - | 0.5 to 1.5 | 1 | times the hover thrust"),
            std::string::npos)
      << schema;
}

}  // namespace
}  // namespace hpa
