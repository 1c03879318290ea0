// The estimator registry: built-in variants, lookup errors that name the known variants, and a
// toy variant registered from outside the library.
#include "hpa/estimator/estimator_registry.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace hpa {
namespace {

// A variant that holds its initial state: the smallest thing the registry can build.
class HoldEstimator final : public Estimator {
 public:
  explicit HoldEstimator(const SystemState& initial) : initial_(initial) {}
  void OnImu(const ImuSample&) override {}
  void OnVio(const VioSample&) override {}
  void OnPayloadDetection(const PayloadDetection&) override {}
  void OnAllocatedThrust(double) override {}
  SystemState Estimate(double time_s) const override {
    SystemState out = initial_;
    out.time_s = time_s;
    return out;
  }
  EstimatorHealth Health() const override { return {}; }

 private:
  SystemState initial_;
};

SystemState Hanging() {
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0, 0, 1);
  s.p_WL_W = Eigen::Vector3d(0, 0, 0.5);
  return s;
}

TEST(EstimatorRegistryTest, ListsTheBuiltInVariants) {
  const std::vector<std::string> names = EstimatorNames();
  ASSERT_GE(names.size(), 2u);
  EXPECT_EQ(names[0], "hybrid");
  EXPECT_EQ(names[1], "always_taut");
  EXPECT_EQ(names[2], "always_taut_projected");
  for (const EstimatorRegistration& registration : Estimators()) {
    EXPECT_FALSE(registration.description.empty()) << registration.name;
    EXPECT_EQ(FindEstimator(registration.name), &registration);
  }
  EXPECT_EQ(FindEstimator("kalman_dream"), nullptr);
}

TEST(EstimatorRegistryTest, BuildsEachBuiltInVariant) {
  const Params params;
  for (const std::string name : {"hybrid", "always_taut"}) {
    const auto estimator = MakeEstimator(name, EstimatorConfig{}, params, Hanging());
    ASSERT_NE(estimator, nullptr) << name;
    const SystemState est = estimator->Estimate(0.0);
    EXPECT_LT((est.p_WL_W - Hanging().p_WL_W).norm(), 1e-12) << name;
    EXPECT_EQ(est.mode, CableMode::kTaut) << name;
  }
}

TEST(EstimatorRegistryTest, UnknownVariantNamesTheKnownOnes) {
  try {
    MakeEstimator("kalman_dream", EstimatorConfig{}, Params{}, Hanging());
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("'kalman_dream'"), std::string::npos) << message;
    EXPECT_NE(message.find("hybrid"), std::string::npos) << message;
    EXPECT_NE(message.find("always_taut"), std::string::npos) << message;
  }
}

TEST(EstimatorRegistryTest, RegistersAToyVariant) {
  // a fresh name per run, so --gtest_repeat does not meet its own earlier registration
  static int run = 0;
  const std::string name = "toy_hold_" + std::to_string(run++);
  const size_t before = Estimators().size();
  RegisterEstimator({name, "holds the initial state",
                     [](const EstimatorConfig&, const Params&, const SystemState& initial) {
                       return std::make_unique<HoldEstimator>(initial);
                     }});
  ASSERT_EQ(Estimators().size(), before + 1);
  EXPECT_EQ(EstimatorNames().back(), name);
  const auto estimator = MakeEstimator(name, EstimatorConfig{}, Params{}, Hanging());
  const SystemState est = estimator->Estimate(3.0);
  EXPECT_EQ(est.time_s, 3.0);
  EXPECT_EQ(est.p_WL_W, Hanging().p_WL_W);

  // a name is registered once; a registration needs a name and a factory
  const EstimatorFactory make = FindEstimator(name)->make;
  EXPECT_THROW(RegisterEstimator({name, "again", make}), std::invalid_argument);
  EXPECT_THROW(RegisterEstimator({"hybrid", "shadowing a built-in", make}), std::invalid_argument);
  EXPECT_THROW(RegisterEstimator({"", "no name", make}), std::invalid_argument);
  EXPECT_THROW(RegisterEstimator({"toy_none", "no factory", nullptr}), std::invalid_argument);
  EXPECT_EQ(Estimators().size(), before + 1);
}

}  // namespace
}  // namespace hpa
