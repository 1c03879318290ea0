// The scenario's world overrides (payload mass, cable length) and the mismatch draw keep each
// field within the one range params.yaml declares for it (models/src/params.cc).
#include <gtest/gtest.h>

#include <string>

#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/sim/world.h"

namespace hpa::sim {
namespace {

std::string OverrideError(double cable_length_m) {
  WorldConfig c;
  c.params = LoadParams(DefaultParamsPath());
  c.overrides.cable_length_m = cable_length_m;
  try {
    World world(c);
  } catch (const InputError& e) {
    return e.what();
  }
  return "accepted";
}

TEST(WorldOverridesTest, ACableLengthOutsideParamsRangeIsNamedWithThatRange) {
  const ParamDecl<Params>& d = FindParamDecl(ParamsTables(), &Params::cable_length_m);
  EXPECT_EQ(OverrideError(d.max), "accepted");
  EXPECT_EQ(OverrideError(d.min), "accepted");
  for (const double bad : {0.0, d.min / 2.0, 2.0 * d.max}) {
    const std::string what = OverrideError(bad);
    EXPECT_NE(what.find("world.cable_length"), std::string::npos) << what;
    EXPECT_NE(what.find("expected " + ParamValueText(d.min) + " to " + ParamValueText(d.max)),
              std::string::npos)
        << what;
  }
}

TEST(WorldOverridesTest, AMismatchDrawStaysWithinTheDeclaredRange) {
  // a sigma far past the cable's length: every draw is brought back into params' range
  const ParamDecl<Params>& d = FindParamDecl(ParamsTables(), &Params::cable_length_m);
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    WorldConfig c;
    c.params = LoadParams(DefaultParamsPath());
    c.seed = seed;
    c.profile.mismatch.enabled = true;
    c.profile.mismatch.cable_length_sigma_m = 100.0;
    const World world(c);
    EXPECT_GE(world.world_params().cable_length_m, d.min);
    EXPECT_LE(world.world_params().cable_length_m, d.max);
  }
}

}  // namespace
}  // namespace hpa::sim
