#include "hpa/controller/reference.h"

#include <gtest/gtest.h>

#include <cmath>

namespace hpa {
namespace {

// Central differences with h = 1e-4 s: truncation error h^2 / 6 * |f'''| is below 1e-7 for
// these trajectories (|f'''| < 1e3) and rounding eps |f| / h about 1e-11; bound 1e-5 leaves
// a margin of about 100x on the measured residual (~1e-7).
constexpr double kFdStepS = 1e-4;
constexpr double kFdTolerance = 1e-5;

void ExpectDerivativesConsistent(const Reference& ref, double t) {
  const ReferencePoint p = ref.At(t);
  const ReferencePoint pp = ref.At(t + kFdStepS);
  const ReferencePoint pm = ref.At(t - kFdStepS);
  const double h2 = 2.0 * kFdStepS;
  EXPECT_TRUE(((pp.p_WL_W - pm.p_WL_W) / h2 - p.v_WL_W).isZero(kFdTolerance)) << "t=" << t;
  EXPECT_TRUE(((pp.v_WL_W - pm.v_WL_W) / h2 - p.a_WL_W).isZero(kFdTolerance)) << "t=" << t;
  EXPECT_TRUE(((pp.a_WL_W - pm.a_WL_W) / h2 - p.j_WL_W).isZero(kFdTolerance)) << "t=" << t;
  EXPECT_TRUE(((pp.p_WQ_W - pm.p_WQ_W) / h2 - p.v_WQ_W).isZero(kFdTolerance)) << "t=" << t;
  EXPECT_TRUE(((pp.v_WQ_W - pm.v_WQ_W) / h2 - p.a_WQ_W).isZero(kFdTolerance)) << "t=" << t;
}

void ExpectFlat(const Params& params, const ReferencePoint& p) {
  // flatness: xi = -(a_L + g e3) / |.|, x_Q = x_L - l xi (1e-12: a few roundings of O(1) numbers)
  const Eigen::Vector3d n = p.a_WL_W + Eigen::Vector3d(0, 0, params.gravity_mps2);
  EXPECT_TRUE((p.xi_W + n.normalized()).isZero(1e-12));
  EXPECT_TRUE((p.p_WQ_W - (p.p_WL_W - params.cable_length_m * p.xi_W)).isZero(1e-12));
}

TEST(ReferenceTest, HoverPutsQuadrotorOneCableLengthAbove) {
  const Params params;
  const auto ref = MakeHoverReference(params, Eigen::Vector3d(1, 2, 0.7));
  const ReferencePoint p = ref->At(3.0);
  EXPECT_TRUE(p.p_WQ_W.isApprox(Eigen::Vector3d(1, 2, 1.2), 1e-12));
  EXPECT_TRUE(p.xi_W.isApprox(Eigen::Vector3d(0, 0, -1), 1e-12));
  EXPECT_TRUE(p.v_WQ_W.isZero(0.0));
  EXPECT_TRUE(p.a_WQ_W.isZero(0.0));
  ExpectFlat(params, p);
}

TEST(ReferenceTest, LissajousStartsAtRestAndReachesFullPhaseRate) {
  const Params params;
  LissajousSpec spec;  // a = 2, b = 0.5, n = 2, T = 5, ramp 2 s
  const auto ref = MakeLissajousReference(params, spec);
  const ReferencePoint p0 = ref->At(0.0);
  EXPECT_TRUE(p0.v_WL_W.isZero(0.0));
  EXPECT_TRUE(p0.a_WL_W.isZero(0.0));
  EXPECT_TRUE(p0.p_WL_W.isApprox(Eigen::Vector3d(0, 0, spec.psi), 1e-12));
  // after the ramp the phase is w (t - ramp / 2): closed form of the velocity
  const double w = 2 * M_PI / spec.period_s;
  const double t = 3.3;
  const double th = w * (t - 0.5 * spec.ramp_s);
  const ReferencePoint p = ref->At(t);
  EXPECT_NEAR(p.p_WL_W.x(), spec.a * std::sin(th), 1e-12);
  EXPECT_NEAR(p.v_WL_W.x(), spec.a * w * std::cos(th), 1e-12);
  EXPECT_NEAR(p.v_WL_W.y(), spec.b * spec.n * w * std::cos(spec.n * th + spec.phi), 1e-12);
  EXPECT_NEAR(p.a_WL_W.x(), -spec.a * w * w * std::sin(th), 1e-12);
}

TEST(ReferenceTest, LissajousDerivativesMatchFiniteDifferences) {
  const Params params;
  LissajousSpec spec;
  spec.c = 0.3;
  spec.m = 1.0;
  spec.phi = 0.4;
  spec.centre = Eigen::Vector3d(0.5, -0.2, 0.1);
  const auto ref = MakeLissajousReference(params, spec);
  for (double t : {0.3, 1.0, 1.7, 2.5, 4.2, 7.9}) {
    ExpectDerivativesConsistent(*ref, t);
    ExpectFlat(params, ref->At(t));
  }
}

TEST(ReferenceTest, LineIsMinimumJerkAndHoldsEnds) {
  const Params params;
  const Eigen::Vector3d a(0, 0, 0.7), b(1, -1, 1.2);
  const auto ref = MakeLineReference(params, a, b, 2.0);
  EXPECT_TRUE(ref->At(-1.0).p_WL_W.isApprox(a, 1e-12));
  EXPECT_TRUE(ref->At(5.0).p_WL_W.isApprox(b, 1e-12));
  EXPECT_TRUE(ref->At(1.0).p_WL_W.isApprox(0.5 * (a + b), 1e-12));  // symmetric time law
  for (double t : {0.2, 0.9, 1.5, 1.9}) ExpectDerivativesConsistent(*ref, t);
}

TEST(ReferenceTest, RejectsBadSpecs) {
  const Params params;
  LissajousSpec spec;
  spec.period_s = 0.0;
  EXPECT_THROW(MakeLissajousReference(params, spec), std::invalid_argument);
  EXPECT_THROW(MakeLineReference(params, Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 0.0),
               std::invalid_argument);
}

}  // namespace
}  // namespace hpa
