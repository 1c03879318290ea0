// A world MuJoCo cannot integrate (it resets mjData on a bad qvel) stops the run with an error
// naming the divergence, never a crash or a silently reset state.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "hpa/models/params.h"
#include "hpa/sim/world.h"

namespace hpa::sim {
namespace {

TEST(WorldDivergenceTest, AVelocityMujocoCannotIntegrateIsARunErrorNamingTheDivergence) {
  WorldConfig c;
  c.params = LoadParams(DefaultParamsPath());
  World world(c);
  world.Step();
  // past MuJoCo's mjMAXVAL (1e10): mj_checkVel resets the state and warns BADQVEL
  world.disturbances().AddVelocity(Body::kPayload, Eigen::Vector3d(1e12, 0, 0));
  try {
    for (int k = 0; k < 10; ++k) world.Step();
    FAIL() << "a payload at 1e12 m/s stepped on";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("the physics diverged"), std::string::npos) << what;
    EXPECT_NE(what.find("not a crash"), std::string::npos) << what;
  }
  EXPECT_FALSE(world.Crash().crashed);
}

}  // namespace
}  // namespace hpa::sim
