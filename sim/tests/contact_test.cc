// The flight profile's world: contact (the payload dropped on the body and on the ground comes to
// rest on the surface, a payload flying into a rotor disk is a rotor_strike crash, the ideal world
// lets it pass through), the model-mismatch draw and the battery sag.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>

#include "hpa/models/params.h"
#include "hpa/sim/world.h"

namespace hpa::sim {
namespace {

WorldConfig ContactConfig(bool contact) {
  WorldConfig c;
  c.params = LoadParams(DefaultParamsPath());
  c.profile.contact.enabled = contact;
  return c;
}

// The quadrotor standing on the ground (box bottom at z = 0, motors idle) and the payload at
// p_WL_W, at rest or with velocity v_WL_W.
void PlaceOnGround(World* world, const Eigen::Vector3d& p_WL_W,
                   const Eigen::Vector3d& v_WL_W = Eigen::Vector3d::Zero()) {
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0, 0, world->world_params().body_half_size_m.z());
  s.p_WL_W = p_WL_W;
  s.v_WL_W = v_WL_W;
  world->SetState(s.ToVector(), InputVector::Constant(world->world_params().motor_speed_min_radps));
  world->SetMotorSpeedCommand(InputVector::Constant(world->world_params().motor_speed_min_radps));
}

TEST(ContactTest, PayloadDroppedOnTheBodyRestsOnItsTop) {
  World world(ContactConfig(true));
  const Params& p = world.world_params();
  const double top_m = 2 * p.body_half_size_m.z();
  // dropped from 0.3 m above the top: 2.4 m/s at impact, 2.4 mm per step
  PlaceOnGround(&world, Eigen::Vector3d(0, 0, top_m + p.payload_radius_m + 0.3));
  double min_distance_m = 1.0, rebound_max_z_m = 0.0;
  bool touched = false;
  for (int k = 0; k < 1500; ++k) {
    world.Step();
    const double z = world.GetTruth().state.p_WL_W.z();
    min_distance_m = std::min(min_distance_m, world.PayloadQuadDistance());
    if (world.contact_counts().payload_body > 0) touched = true;
    if (touched) rebound_max_z_m = std::max(rebound_max_z_m, z);
  }
  const Truth t = world.GetTruth();
  // never overlaps the body: the contact margin stops it first
  EXPECT_GT(min_distance_m, 0.0);
  // rests on the top, the margin above it, within 1 mm (the quadrotor itself stands on the
  // ground the same margin up)
  const double top_now_m = t.state.p_WQ_W.z() + p.body_half_size_m.z();
  const double rest_z_m = top_now_m + p.payload_radius_m + World::kContactMargin_m;
  EXPECT_NEAR(t.state.p_WL_W.z(), rest_z_m, 0.001);
  EXPECT_LT(t.state.v_WL_W.norm(), 0.01);
  // a hard contact: no bounce back up by more than 1 cm
  EXPECT_LT(rebound_max_z_m, rest_z_m + 0.01);
  // the impact and at most one re-contact after a sub-centimetre hop (measured: 2)
  EXPECT_GE(world.contact_counts().payload_body, 1);
  EXPECT_LE(world.contact_counts().payload_body, 2);
  EXPECT_NE(world.Crash().reason, "rotor_strike");
}

TEST(ContactTest, PayloadDroppedOnTheGroundRestsOnIt) {
  World world(ContactConfig(true));
  const double r = world.world_params().payload_radius_m;
  PlaceOnGround(&world, Eigen::Vector3d(0.3, 0, r + 0.3));
  double min_z_m = 1.0;
  for (int k = 0; k < 1500; ++k) {
    world.Step();
    min_z_m = std::min(min_z_m, world.GetTruth().state.p_WL_W.z());
  }
  const Truth t = world.GetTruth();
  // sinks at most 2 mm at the impact (MuJoCo's soft contact; measured about 1 mm) and rests
  // within 1 mm of the surface
  EXPECT_GT(min_z_m, r - 0.002);
  EXPECT_NEAR(t.state.p_WL_W.z(), r, 0.001);
  EXPECT_LT(t.state.v_WL_W.norm(), 0.01);
  // the impact and at most one re-contact after a sub-centimetre hop (measured: 2)
  EXPECT_GE(world.contact_counts().payload_ground, 1);
  EXPECT_LE(world.contact_counts().payload_ground, 2);
}

// The payload shot up at 5 m/s under rotor 0 (beside the body box, under the rotor disk).
std::unique_ptr<World> ShootIntoRotor(bool contact, double* min_distance_m) {
  auto owned = std::make_unique<World>(ContactConfig(contact));
  World& world = *owned;
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0, 0, 1.0);
  s.p_WL_W = Eigen::Vector3d(0.15, 0.15, 0.8);
  s.v_WL_W = Eigen::Vector3d(0, 0, 5.0);
  const double w_hover = world.world_params().HoverMotorSpeedRadps();
  world.SetState(s.ToVector(), InputVector::Constant(w_hover));
  *min_distance_m = 1.0;
  for (int k = 0; k < 150 && !world.Crash().crashed; ++k) {
    world.Step();
    *min_distance_m = std::min(*min_distance_m, world.PayloadQuadDistance());
  }
  return owned;
}

TEST(ContactTest, PayloadReachingARotorDiskIsARotorStrike) {
  double min_distance_m = 0;
  const World& world = *ShootIntoRotor(true, &min_distance_m);
  EXPECT_TRUE(world.Crash().crashed);
  EXPECT_EQ(world.Crash().reason, "rotor_strike");
  EXPECT_EQ(world.contact_counts().payload_rotor, 1);
  // struck within the margin before it overlaps: 5 mm per step against the margin
  EXPECT_GE(world.payload_quad_min_distance_m(), 0.0);
}

TEST(ContactTest, IdealWorldLetsThePayloadPassThroughTheVehicle) {
  double min_distance_m = 0;
  const World& world = *ShootIntoRotor(false, &min_distance_m);
  EXPECT_FALSE(world.Crash().crashed);
  EXPECT_EQ(world.contact_counts().payload_rotor, 0);
  EXPECT_LT(world.payload_quad_min_distance_m(), -0.01);
}

}  // namespace
}  // namespace hpa::sim

namespace hpa::sim {
namespace {

WorldConfig MismatchConfig(uint64_t seed) {
  WorldConfig c;
  c.params = LoadParams(DefaultParamsPath());
  c.seed = seed;
  c.profile.mismatch = {true, 0.002, 0.005, 0.1, 0.005, 0.03, 0.002, 0.0087};
  c.profile.actuation = {true, 0.02, 0.03, 2.8e-4};
  return c;
}

TEST(ProfileTest, MismatchIsADrawPerSeedWithinItsTolerance) {
  const Params flight = LoadParams(DefaultParamsPath());
  World a(MismatchConfig(1)), a_again(MismatchConfig(1)), b(MismatchConfig(2));
  const Params& pa = a.world_params();
  // the world differs from the flight code's numbers, the same way for the same seed
  EXPECT_NE(pa.payload_mass_kg, flight.payload_mass_kg);
  EXPECT_NE(pa.cable_length_m, flight.cable_length_m);
  EXPECT_NE(pa.k_f_N_per_radps2, flight.k_f_N_per_radps2);
  EXPECT_FALSE(pa.t_BC_B_m.isApprox(flight.t_BC_B_m));
  EXPECT_EQ(pa.payload_mass_kg, a_again.world_params().payload_mass_kg);
  EXPECT_NE(pa.payload_mass_kg, b.world_params().payload_mass_kg);
  // within 5 sigma of the tolerances
  EXPECT_NEAR(pa.payload_mass_kg, flight.payload_mass_kg, 5 * 0.002);
  EXPECT_NEAR(pa.cable_length_m, flight.cable_length_m, 5 * 0.005);
  // the per-rotor spread is drawn too, and the ideal world has none
  EXPECT_FALSE(a.rotor_thrust_factor().isApproxToConstant(1.0));
  WorldConfig ideal;
  ideal.params = flight;
  World w(ideal);
  EXPECT_TRUE(w.rotor_thrust_factor().isApproxToConstant(1.0));
  EXPECT_EQ(w.world_params().payload_mass_kg, flight.payload_mass_kg);
}

TEST(ProfileTest, BatterySagLowersTheSpeedACommandReaches) {
  World world(MismatchConfig(1));
  EXPECT_DOUBLE_EQ(world.BatterySpeedFactor(), 1.0);
  for (int k = 0; k < 1000; ++k) world.Step();
  // linear voltage drop: 1 - 2.8e-4 / s * 1 s
  EXPECT_NEAR(world.BatterySpeedFactor(), 1.0 - 2.8e-4, 1e-12);
}

}  // namespace
}  // namespace hpa::sim
