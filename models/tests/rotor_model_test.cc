#include "hpa/models/rotor_model.h"

#include <gtest/gtest.h>

namespace hpa {
namespace {

TEST(RotorModelTest, HoverSpeedsGiveHoverThrustAndNoMoment) {
  const Params p;
  const InputVector w = InputVector::Constant(p.HoverMotorSpeedRadps());
  const Eigen::Vector4d wrench = WrenchFromRotorSpeeds(p, w);
  EXPECT_NEAR(wrench(0), p.HoverThrustN(), 1e-9);
  EXPECT_NEAR(wrench.tail<3>().norm(), 0.0, 1e-12);
}

TEST(RotorModelTest, MomentSigns) {
  const Params p;
  InputVector w = InputVector::Constant(1000.0);
  // faster rotors on +y side roll the body positively about x
  w(0) += 100;
  w(1) += 100;
  EXPECT_GT(WrenchFromRotorSpeeds(p, w)(1), 0.0);
  // faster rotors on +x side pitch negatively about y (r x f = -r_x f about y)
  w = InputVector::Constant(1000.0);
  w(0) += 100;
  w(3) += 100;
  EXPECT_LT(WrenchFromRotorSpeeds(p, w)(2), 0.0);
}

TEST(RotorModelTest, InverseRoundTrips) {
  const Params p;
  const Eigen::Vector4d wrench(8.0, 0.01, -0.02, 0.003);
  const InputVector w = RotorSpeedsFromWrench(p, wrench);
  EXPECT_LT((WrenchFromRotorSpeeds(p, w) - wrench).norm(), 1e-9);
}

}  // namespace
}  // namespace hpa
