// The controller registry: the built-ins, a toy controller registered at run time, refusals.

#include "hpa/controller/controller_registry.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace hpa {
namespace {

// Holds the hover thrust, zero body rates: the smallest controller there is (it still says
// when its input is not finite, as every controller must).
class ToyController : public Controller {
 public:
  explicit ToyController(const Params& params) : thrust_N_(params.HoverThrustN()) {}
  ControlOutput Update(const SystemState& state) override {
    ControlOutput out;
    out.command.thrust_N = thrust_N_;
    if (!state.AllFinite()) out.status = ControlStatus::kNonFinite;
    return out;
  }
  double RateHz() const override { return 50.0; }

 private:
  double thrust_N_;
};

std::shared_ptr<const Reference> Hover(const Params& params) {
  return MakeHoverReference(params, Eigen::Vector3d(0, 0, 0.7));
}

TEST(ControllerRegistryTest, ListsTheBuiltInsWithTheirEstimators) {
  const std::vector<std::string> names = ControllerNames();
  ASSERT_GE(names.size(), 3u);
  EXPECT_EQ(names[0], "hpa_mpc");
  EXPECT_EQ(names[1], "nonhybrid_mpc");
  EXPECT_EQ(names[2], "geometric");
  EXPECT_EQ(FindController("hpa_mpc")->estimator, "hybrid");
  EXPECT_EQ(FindController("nonhybrid_mpc")->estimator, "always_taut");
  for (const ControllerRegistration& r : Controllers()) {
    EXPECT_FALSE(r.description.empty()) << r.name;
    ControllerConfig config;
    config.type = r.name;
    const Params params;
    EXPECT_NE(MakeController(config, params, Hover(params)), nullptr) << r.name;
  }
  EXPECT_EQ(FindController("pid"), nullptr);
}

TEST(ControllerRegistryTest, AToyControllerIsOneRegistration) {
  if (FindController("toy_hold") == nullptr) {
    RegisterController(
        {"toy_hold", "holds the hover thrust", "hybrid",
         [](const ControllerConfig&, const Params& params, std::shared_ptr<const Reference>) {
           return std::make_unique<ToyController>(params);
         }});
  }
  ControllerConfig config;
  config.type = "toy_hold";
  const Params params;
  const std::unique_ptr<Controller> toy = MakeController(config, params, Hover(params));
  ASSERT_NE(toy, nullptr);
  EXPECT_DOUBLE_EQ(toy->RateHz(), 50.0);
  EXPECT_DOUBLE_EQ(toy->Update(SystemState{}).command.thrust_N, params.HoverThrustN());
  EXPECT_EQ(ControllerNames().back(), "toy_hold");
}

TEST(ControllerRegistryTest, DuplicatesEmptyNamesAndMissingFactoriesAreRefused) {
  const ControllerFactory make = [](const ControllerConfig&, const Params& params,
                                    std::shared_ptr<const Reference>) {
    return std::make_unique<ToyController>(params);
  };
  EXPECT_THROW(RegisterController({"hpa_mpc", "again", "hybrid", make}), std::invalid_argument);
  EXPECT_THROW(RegisterController({"", "nameless", "hybrid", make}), std::invalid_argument);
  EXPECT_THROW(RegisterController({"no_factory", "x", "hybrid", nullptr}), std::invalid_argument);
}

TEST(ControllerRegistryTest, UnknownTypeAndSolverNameTheKnownOnes) {
  const Params params;
  ControllerConfig config;
  config.type = "pid";
  try {
    MakeController(config, params, Hover(params));
    FAIL() << "pid accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("nonhybrid_mpc"), std::string::npos) << e.what();
  }
  config.type = "hpa_mpc";
  config.settings["solver"] = std::string("ipopt");
  EXPECT_THROW(MakeController(config, params, Hover(params)), std::invalid_argument);
}

}  // namespace
}  // namespace hpa
