// The flight profile's world: contact (the payload dropped on the body and on the ground comes to
// rest on the surface, a payload flying into a rotor disk is a rotor_strike crash, a free
// gripper's rod stops a falling payload, a held one meets no contact, the ideal world lets it
// pass through), the model-mismatch draw and the battery sag.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "hpa/models/params.h"
#include "hpa/sim/sensor_models.h"
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
    min_distance_m = std::min(min_distance_m, world.contacts().PayloadQuadDistance());
    if (world.contacts().counts().payload_body > 0) touched = true;
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
  EXPECT_GE(world.contacts().counts().payload_body, 1);
  EXPECT_LE(world.contacts().counts().payload_body, 2);
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
  EXPECT_GE(world.contacts().counts().payload_ground, 1);
  EXPECT_LE(world.contacts().counts().payload_ground, 2);
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
    *min_distance_m = std::min(*min_distance_m, world.contacts().PayloadQuadDistance());
  }
  return owned;
}

TEST(ContactTest, PayloadReachingARotorDiskIsARotorStrike) {
  double min_distance_m = 0;
  const std::unique_ptr<World> owned = ShootIntoRotor(true, &min_distance_m);
  const World& world = *owned;
  EXPECT_TRUE(world.Crash().crashed);
  EXPECT_EQ(world.Crash().reason, "rotor_strike");
  EXPECT_EQ(world.contacts().counts().payload_rotor, 1);
  // struck within the margin before it overlaps: 5 mm per step against the margin
  EXPECT_GE(world.contacts().payload_quad_min_distance_m(), 0.0);
}

TEST(ContactTest, IdealWorldLetsThePayloadPassThroughTheVehicle) {
  double min_distance_m = 0;
  const std::unique_ptr<World> owned = ShootIntoRotor(false, &min_distance_m);
  const World& world = *owned;
  EXPECT_FALSE(world.Crash().crashed);
  EXPECT_EQ(world.contacts().counts().payload_rotor, 0);
  EXPECT_LT(world.contacts().payload_quad_min_distance_m(), -0.01);
}

// The gripper's rod (capsule from 0.045 m to 0.3 m below the gripper's origin, radius 0.02 m):
// with the gripper at (0.2, 0, 0.3) its top end is at (0.2, 0, 0.255), its top surface at 0.275.
constexpr double kRodTopSurfaceZ_m = 0.275;

// A free gripper at (0.2, 0, 0.3), the payload dropped onto its rod from 0.1 m above the top.
std::unique_ptr<World> DropOnGripperRod(bool contact, double* min_z_m) {
  auto owned = std::make_unique<World>(ContactConfig(contact));
  World& world = *owned;
  const double r = world.world_params().payload_radius_m;
  PlaceOnGround(&world, Eigen::Vector3d(0.2, 0, kRodTopSurfaceZ_m + r + 0.1));
  world.gripper().Move(Eigen::Vector3d(0.2, 0, 0.3), 0.001);
  *min_z_m = 1.0;
  for (int k = 0; k < 300; ++k) {
    world.Step();
    *min_z_m = std::min(*min_z_m, world.GetTruth().state.p_WL_W.z());
  }
  return owned;
}

TEST(ContactTest, PayloadFallingOnAFreeGripperStrikesItsRod) {
  double min_z_m = 0.0;
  const std::unique_ptr<World> world = DropOnGripperRod(true, &min_z_m);
  const double r = world->world_params().payload_radius_m;
  // stopped on the rod's top (1.4 m/s at impact, 1.4 mm per step): sinks at most 3 mm into it
  // (MuJoCo's soft contact with the payload's 2 ms solref; measured 1.0 mm, two contact
  // episodes: the impact and one re-contact after a hop)
  EXPECT_GT(min_z_m, kRodTopSurfaceZ_m + r - 0.003);
  EXPECT_GE(world->contacts().counts().payload_gripper, 1);
  // the quadrotor standing on the ground latches its ground crash; the payload's strike is none
  EXPECT_EQ(world->Crash().reason.find("gripper"), std::string::npos) << world->Crash().reason;
}

// A gripper no event has used is not in the world: the rod at the scene's default place (top
// surface at 0.475 m, under (0, 0, 0.5)) does not stop a payload dropped onto it.
TEST(ContactTest, UnusedGripperIsNotThere) {
  World world(ContactConfig(true));
  const double r = world.world_params().payload_radius_m;
  PlaceOnGround(&world, Eigen::Vector3d(0.0, 0, 0.475 + r + 0.1));
  double min_z_m = 1.0;
  for (int k = 0; k < 400; ++k) {
    world.Step();
    min_z_m = std::min(min_z_m, world.GetTruth().state.p_WL_W.z());
  }
  // fell through the rod's place (top surface 0.475 m) until the cable to the grounded
  // quadrotor held it
  EXPECT_LT(min_z_m, 0.3);
  EXPECT_EQ(world.contacts().counts().payload_gripper, 0);
}

TEST(ContactTest, IdealWorldLetsThePayloadPassThroughTheGripper) {
  double min_z_m = 0.0;
  const std::unique_ptr<World> world = DropOnGripperRod(false, &min_z_m);
  // free fall for 0.3 s from 0.415 m: down to the ground, past the rod
  EXPECT_LT(min_z_m, 0.1);
  EXPECT_EQ(world->contacts().counts().payload_gripper, 0);
}

// Grab, lift, hold and release: the payload's path with flight contact equals the ideal world's
// while held (no contact fights the weld) and while it falls clear of the rod after the release.
TEST(ContactTest, HeldPayloadAndItsReleaseMeetNoGripperContact) {
  std::vector<Eigen::Vector3d> path[2];
  int gripper_contacts[2] = {0, 0};
  for (int contact = 0; contact < 2; ++contact) {
    World world(ContactConfig(contact == 1));
    PlaceOnGround(&world, Eigen::Vector3d(0.2, 0, 0.3));
    world.gripper().Grab();  // the rod now overlaps the payload's lower half
    world.gripper().Move(Eigen::Vector3d(0.2, 0, 0.35), 0.1);
    for (int k = 0; k < 400; ++k) {
      if (k == 200) world.gripper().Release();
      world.Step();
      path[contact].push_back(world.GetTruth().state.p_WL_W);
    }
    gripper_contacts[contact] = world.contacts().counts().payload_gripper;
  }
  // 200 ms held, then 200 ms of fall (0.2 m: past the rod's lower end, 0.3 m below the centre,
  // the ground at 0.04 m not yet reached); identical to rounding (1e-12 m)
  for (size_t k = 0; k < path[0].size(); ++k) {
    EXPECT_LT((path[1][k] - path[0][k]).norm(), 1e-12) << "step " << k;
  }
  EXPECT_GT(path[1][199].z() - path[1].back().z(), 0.15);
  EXPECT_EQ(gripper_contacts[1], 0);
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
  EXPECT_FALSE(a.vehicle().rotor_thrust_factor().isApproxToConstant(1.0));
  WorldConfig ideal;
  ideal.params = flight;
  World w(ideal);
  EXPECT_TRUE(w.vehicle().rotor_thrust_factor().isApproxToConstant(1.0));
  EXPECT_EQ(w.world_params().payload_mass_kg, flight.payload_mass_kg);
}

TEST(ProfileTest, BatterySagLowersTheSpeedACommandReaches) {
  World world(MismatchConfig(1));
  EXPECT_DOUBLE_EQ(world.vehicle().BatterySpeedFactor(), 1.0);
  for (int k = 0; k < 1000; ++k) world.Step();
  // linear voltage drop: 1 - 2.8e-4 / s * 1 s
  EXPECT_NEAR(world.vehicle().BatterySpeedFactor(), 1.0 - 2.8e-4, 1e-12);
}

}  // namespace
}  // namespace hpa::sim

namespace hpa::sim {
namespace {

WorldConfig AeroConfig() {
  WorldConfig c;
  c.params = LoadParams(DefaultParamsPath());
  c.profile.aero = {true, 1.225, 0.39168, 0.27792, 1.05, 1.17, 0.47};
  return c;
}

// Level quadrotor at hover speed moving at v_WQ_W, payload hanging and moving with it.
void Moving(World* world, const Eigen::Vector3d& v_W_mps) {
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0, 0, 1.0);
  s.p_WL_W = Eigen::Vector3d(0, 0, 0.5);
  s.v_WQ_W = v_W_mps;
  s.v_WL_W = v_W_mps;
  world->SetState(s.ToVector(),
                  InputVector::Constant(world->world_params().HoverMotorSpeedRadps()));
}

TEST(AeroTest, DragOpposesTheAirspeedWithTheClosedFormMagnitude) {
  World world(AeroConfig());
  const Params& p = world.world_params();
  Moving(&world, Eigen::Vector3d(3.0, 0, 0));
  world.Step();
  // rotor drag d_x v plus the body's 0.5 rho Cd A v^2 over its 0.2 x 0.06 m face
  (void)p;
  const double expected_N = 0.39168 * 3.0 + 0.5 * 1.225 * 1.05 * (0.2 * 0.06) * 9.0;
  EXPECT_NEAR(world.disturbances().aero_quad_W_N().x(), -expected_N, 1e-9);
  EXPECT_NEAR(world.disturbances().aero_quad_W_N().y(), 0.0, 1e-9);
  // the payload sphere: 0.5 rho Cd pi r^2 v^2
  const double payload_N = 0.5 * 1.225 * 0.47 * M_PI * 0.04 * 0.04 * 9.0;
  EXPECT_NEAR(world.disturbances().aero_payload_W_N().x(), -payload_N, 1e-9);
}

TEST(AeroTest, NoDragWhenMovingWithTheWindOrWhenOff) {
  WorldConfig c = AeroConfig();
  c.profile.wind.mean_x_mps = 3.0;
  World with_wind(c);
  Moving(&with_wind, Eigen::Vector3d(3.0, 0, 0));
  with_wind.Step();
  EXPECT_LT(with_wind.disturbances().aero_quad_W_N().norm(), 1e-9);
  EXPECT_LT(with_wind.disturbances().aero_payload_W_N().norm(), 1e-9);
  c.profile.aero.enabled = false;
  World off(c);
  Moving(&off, Eigen::Vector3d(3.0, 0, 0));
  off.Step();
  EXPECT_EQ(off.disturbances().aero_quad_W_N().norm(), 0.0);
}

TEST(WindTest, GustHasItsStationaryStdAndCorrelationTime) {
  WorldConfig c = AeroConfig();
  c.profile.wind.gust_sigma_mps = 1.0;
  c.profile.wind.gust_length_m = 0.2;  // at the 1 m/s floor: tau = 0.2 s
  World world(c);
  std::vector<double> gust;
  for (int k = 0; k < 60000; ++k) {
    if (k % 100 == 0) Moving(&world, Eigen::Vector3d::Zero());  // keep the vehicle at rest
    world.Step();
    gust.push_back(world.disturbances().Wind_W_mps().x());
  }
  double sum = 0, sq = 0, lag = 0;
  for (double g : gust) sum += g, sq += g * g;
  const double n = static_cast<double>(gust.size()), mean = sum / n, var = sq / n - mean * mean;
  for (size_t k = 200; k < gust.size(); ++k) lag += (gust[k] - mean) * (gust[k - 200] - mean);
  // 60 s / 0.2 s = 300 correlation times. Measured over seeds 1-5: std 0.94-1.08, lag-tau
  // autocorrelation 0.34-0.47 (exp(-1) = 0.37); bounds 3x that spread.
  EXPECT_NEAR(std::sqrt(var), 1.0, 0.2);
  EXPECT_NEAR(lag / (n - 200) / var, std::exp(-1.0), 0.15);
}

TEST(VioDriftTest, DriftGrowsWithTheSquareRootOfDistanceAndIsOffByDefault) {
  SensorNoiseConfig noise;
  VioDriftProfile drift{true, 0.0158, 0.0158, 0.0, 0.0, 0.0, 1.0};
  // many vehicles flying 100 m straight in 1 m captures: drift std sigma sqrt(100) per axis
  double sq = 0;
  constexpr int kRuns = 400;
  for (int run = 0; run < kRuns; ++run) {
    std::mt19937_64 rng(run);
    VioModel vio(noise, 0.0, &rng);
    vio.SetDrift(drift, 1000 + run);
    for (int k = 0; k <= 100; ++k) vio.Capture(k * 0.1, Eigen::Vector3d(k, 0, 0), {1, 0, 0, 0}, {});
    sq += vio.drift_W_m().squaredNorm() / 3.0;
  }
  // std of a std estimate over 1200 samples: 2 %; bound 8 %
  EXPECT_NEAR(std::sqrt(sq / kRuns), 0.0158 * 10.0, 0.08 * 0.158);
  // hovering in place: no drift
  std::mt19937_64 rng(1);
  VioModel still(noise, 0.0, &rng);
  still.SetDrift(drift, 7);
  for (int k = 0; k < 100; ++k) still.Capture(k * 0.03, Eigen::Vector3d(1, 2, 3), {1, 0, 0, 0}, {});
  EXPECT_EQ(still.drift_W_m().norm(), 0.0);
  // off: the same samples as a model that never heard of drift
  std::mt19937_64 rng_a(5), rng_b(5);
  VioModel plain(noise, 0.0, &rng_a), disabled(noise, 0.0, &rng_b);
  disabled.SetDrift(VioDriftProfile{}, 9);
  for (int k = 0; k < 10; ++k) {
    plain.Capture(k * 0.03, Eigen::Vector3d(k, 0, 1), {1, 0, 0, 0}, {1, 0, 0});
    disabled.Capture(k * 0.03, Eigen::Vector3d(k, 0, 1), {1, 0, 0, 0}, {1, 0, 0});
    EXPECT_EQ(plain.Take(1.0)->p_WB_W, disabled.Take(1.0)->p_WB_W);
  }
}

TEST(VioDriftTest, DropoutsWithholdSamplesAndEndInAJump) {
  SensorNoiseConfig noise;
  VioDriftProfile drift{true, 0.05, 0.05, 0.0, 2.0, 0.3, 0.0};  // frequent dropouts, full reset
  std::mt19937_64 rng(3);
  VioModel vio(noise, 0.0, &rng);
  vio.SetDrift(drift, 11);
  int delivered = 0, captured = 0;
  for (int k = 0; k < 3000; ++k) {
    vio.Capture(k / 30.0, Eigen::Vector3d(0.1 * k, 0, 1), {1, 0, 0, 0}, {});
    ++captured;
    while (vio.Take(1e9)) ++delivered;
  }
  // renewal process: a dropout of 0.3 s starts at 2 per s of tracking: missing share
  // 2 * 0.3 / (1 + 2 * 0.3) = 0.375 (capture rounding adds a frame per dropout); bound +-0.08
  const double missing = 1.0 - static_cast<double>(delivered) / captured;
  EXPECT_NEAR(missing, 0.375, 0.08);
}

}  // namespace
}  // namespace hpa::sim
