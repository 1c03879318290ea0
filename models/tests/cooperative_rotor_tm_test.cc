// The cooperative model (hpa::CooperativeModel) against an independent, line-by-line transcription
// of RotorTM's cooperative cable-suspended payload simulator (rotor_tm_transcription.h): the
// state derivative, all cables taut or each taut or slack, and the re-taut collision, on random
// teams of 1 to 3 vehicles.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstdio>
#include <random>
#include <vector>

#include "hpa/models/cooperative_model.h"
#include "models/tests/cooperative_test_support.h"
#include "models/tests/rotor_tm_transcription.h"

namespace hpa {
namespace {

using Eigen::VectorXd;
using I = CooperativeStateIndex;
using cooperative_test::kRotorTmTolerance;
using cooperative_test::RandomRotorSpeeds;
using cooperative_test::RandomTautState;
using cooperative_test::RandomTeam;
using cooperative_test::RandomVector;
using cooperative_test::RelativeDifference;
using rotor_tm::RotorTmDerivative;
using rotor_tm::RotorTmSimulation;
using rotor_tm::ToRotorTm;

class CooperativeRotorTmTest : public testing::TestWithParam<int> {};

// The model's derivative against RotorTM's on 1000 random teams of `n` vehicles drawn from
// `seed`, every cable taut or (`mixed_modes`) each taut or slack at random (the slack ones left
// where the taut layout put them); fails at the first trial beyond kRotorTmTolerance and prints
// the largest difference as `label`.
void ExpectDerivativeEqualsRotorTm(int n, unsigned seed, bool mixed_modes, const char* label) {
  std::mt19937 rng(seed);
  double worst = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const CooperativeTeam team = RandomTeam(n, &rng);
    const CooperativeModel model(team);
    const VectorXd x = RandomTautState(team, &rng);
    const VectorXd u = RandomRotorSpeeds(n, &rng);
    std::vector<CableMode> modes(n, CableMode::kTaut);
    if (mixed_modes) {
      for (int i = 0; i < n; ++i) modes[i] = rng() % 2 ? CableMode::kTaut : CableMode::kSlack;
    }
    const double diff =
        RelativeDifference(model.Derivative(x, u, modes), RotorTmDerivative(team, x, u, modes));
    worst = std::max(worst, diff);
    ASSERT_LT(diff, kRotorTmTolerance) << label << ", trial " << trial;
  }
  std::printf("[measured] N = %d %s: largest relative difference to RotorTM %.2e\n", n, label,
              worst);
}

TEST_P(CooperativeRotorTmTest, TautDerivativeEqualsRotorTmTranscription) {
  ExpectDerivativeEqualsRotorTm(GetParam(), 1000 + GetParam(), false, "taut");
}

TEST_P(CooperativeRotorTmTest, MixedModesEqualRotorTmTranscription) {
  ExpectDerivativeEqualsRotorTm(GetParam(), 2000 + GetParam(), true, "mixed modes");
}

TEST_P(CooperativeRotorTmTest, RetautCollisionEqualsRotorTmTranscription) {
  // cables at their length, stretching at random speeds; a random subset collides
  const int n = GetParam();
  std::mt19937 rng(3000 + n);
  double worst = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const CooperativeTeam team = RandomTeam(n, &rng);
    const CooperativeModel model(team);
    VectorXd x = RandomTautState(team, &rng);
    std::vector<bool> colliding(n);
    std::vector<int> collision_idx(n);
    for (int i = 0; i < n; ++i) {
      x.segment<3>(I::Vehicle(i) + I::kVehicleVel) += RandomVector(&rng);
      colliding[i] = trial % 2 == 0 || rng() % 2 == 1;
      collision_idx[i] = colliding[i] ? 1 : 0;
    }
    RotorTmSimulation sim =
        ToRotorTm(team, std::vector<CableMode>(n, CableMode::kTaut), VectorXd::Zero(4 * n));
    const VectorXd expected = sim.rigidbody_quad_inelastic_cable_collision(x, collision_idx);
    const double diff = RelativeDifference(model.RetautCollision(x, colliding), expected);
    worst = std::max(worst, diff);
    ASSERT_LT(diff, kRotorTmTolerance) << "trial " << trial;
  }
  std::printf("[measured] N = %d re-taut collision: largest relative difference to RotorTM %.2e\n",
              n, worst);
}

INSTANTIATE_TEST_SUITE_P(CooperativeTeams, CooperativeRotorTmTest, testing::Values(1, 2, 3));

}  // namespace
}  // namespace hpa
