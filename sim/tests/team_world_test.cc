// hpa::sim::TeamWorld: a team of quadrotors on their own cables carrying one payload, in MuJoCo.
// Hover from Reset, the truth after Reset, the motion-capture delivery and noise, the crash
// conditions, a slack cable after an impulse, determinism and bad input.
#include "hpa/sim/team_world.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "hpa/models/cooperative_model.h"
#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/sim/cooperative_scene.h"
#include "sim/tests/test_teams.h"

namespace hpa::sim {
namespace {

using Eigen::Vector3d;
using Eigen::VectorXd;
using I = CooperativeStateIndex;

TeamWorldConfig Config(const CooperativeTeam& team, uint64_t seed = 1) {
  TeamWorldConfig c;
  c.team = team;
  c.seed = seed;
  return c;
}

// The payload resting on the ground, level, each vehicle hovering slack above its attachment
// point at height_m above the ground.
VectorXd PayloadOnGround(const CooperativeTeam& team, double height_m) {
  const CooperativeModel model(team);
  VectorXd x = model.HangingState(Vector3d(0, 0, team.vehicles.front().params.payload_radius_m));
  for (int i = 0; i < model.VehicleCount(); ++i) {
    x(I::Vehicle(i) + 2) = height_m;
  }
  return x;
}

// (a) A hanging team held at the Reset's motor speeds: the payload stays where it was and every
// cable stays taut. The Reset's speeds balance each vehicle's weight and its cable's share
// exactly, so what moves the payload is only the soft cable limit taking up the load in the
// first steps (the payload falls one step before the limit engages, then settles where the
// limit's stretch carries it) and rounding. The 5 cm bound sits far above that and far below
// what a wrong share does: an unbalanced thrust of a tenth of a vehicle's weight moves it
// g / 10 * t^2 / 2, about 2 m in 2 s.
void ExpectHoldsHover(const CooperativeTeam& team) {
  TeamWorld world(Config(team));
  const CooperativeModel model(team);
  const VectorXd x0 = model.HangingState(Vector3d(0.5, -0.3, 1.5));
  world.Reset(x0);
  double drift_m = 0.0;
  bool all_taut = true;
  for (int s = 0; s < 2000; ++s) {
    world.Step();
    const TeamTruth t = world.GetTruth();
    drift_m = std::max(drift_m, (t.x.segment<3>(I::kPayloadPos) - x0.segment<3>(0)).norm());
    for (CableMode mode : t.modes) all_taut &= mode == CableMode::kTaut;
  }
  const TeamTruth t = world.GetTruth();
  double tension_sum_N = 0.0;
  for (double tension_N : t.cable_tension_N) tension_sum_N += tension_N;
  std::printf(
      "[measured] N = %d hover, 2 s: payload drift %.2e m, tension sum %.4f N (weight %.4f)\n",
      world.VehicleCount(), drift_m, tension_sum_N, team.payload_mass_kg * team.gravity_mps2);
  EXPECT_LT(drift_m, 0.05);
  EXPECT_TRUE(all_taut);
  EXPECT_FALSE(world.Crash().crashed) << world.Crash().reason;
  // the tensions are positive pulls that carry the payload at rest: their sum is its weight
  // but for what is left of the soft limit's settling oscillation, well inside 1 %
  EXPECT_NEAR(tension_sum_N, team.payload_mass_kg * team.gravity_mps2,
              0.01 * team.payload_mass_kg * team.gravity_mps2);
  for (double tension_N : t.cable_tension_N) EXPECT_GT(tension_N, 0.0);
}

TEST(TeamWorldTest, TwoVehiclesHoldTheBarAtHover) { ExpectHoldsHover(TestBar()); }

TEST(TeamWorldTest, ThreeVehiclesHoldThePlateAtHover) { ExpectHoldsHover(TestTriangle()); }

TEST(TeamWorldTest, OneVehicleHoldsAPointPayloadAtHover) {
  ExpectHoldsHover(CooperativeTeam::SingleVehicle(LoadParams(DefaultParamsPath())));
}

// (b) Reset writes the state MuJoCo holds: the truth is x0 up to MuJoCo's copy of it.
TEST(TeamWorldTest, TruthAfterResetIsTheResetState) {
  const CooperativeTeam team = TestTriangle();
  TeamWorld world(Config(team));
  const CooperativeModel model(team);
  VectorXd x0 = model.HangingState(Vector3d(0.1, 0.2, 1.2));
  // moving and turning bodies, tilted attitudes (unit quaternions), rates in the body frames
  for (int body = 0; body <= 3; ++body) {
    const int at = I::kBlockSize * body;
    x0.segment<3>(at + 3) = Vector3d(0.3, -0.2, 0.1) * (body + 1);
    const Eigen::Quaterniond q(Eigen::AngleAxisd(0.1 * (body + 1), Vector3d(1, 2, 3).normalized()));
    x0.segment<4>(at + 6) << q.w(), q.x(), q.y(), q.z();
    x0.segment<3>(at + 10) = Vector3d(0.2, -0.1, 0.3) * (body + 1);
  }
  world.Reset(x0);
  const TeamTruth t = world.GetTruth();
  EXPECT_EQ(t.time_s, 0.0);
  ASSERT_EQ(t.x.size(), x0.size());
  // the quaternions are normalised on the way in: a unit one changes by rounding only
  EXPECT_LT((t.x - x0).cwiseAbs().maxCoeff(), 1e-12);
  ASSERT_EQ(t.cable_length_m.size(), 3u);
  ASSERT_EQ(t.modes.size(), 3u);
  EXPECT_EQ(t.motor_speed_radps.size(), 12);
}

// The Reset's motor speeds: a slack cable's vehicle holds its own weight only.
TEST(TeamWorldTest, ResetHoldsASlackVehicleAtItsOwnHover) {
  const CooperativeTeam team = TestBar();
  TeamWorld world(Config(team));
  world.Reset(PayloadOnGround(team, 0.4));
  const TeamTruth t = world.GetTruth();
  const Params& p = team.vehicles[0].params;
  const double w_own_radps = std::sqrt(p.quad_mass_kg * p.gravity_mps2 / 4 / p.k_f_N_per_radps2);
  for (CableMode mode : t.modes) EXPECT_EQ(mode, CableMode::kSlack);
  // RotorSpeedsFromWrench's allocation inverse rounds each rotor's share
  EXPECT_LT((t.motor_speed_radps.array() - w_own_radps).abs().maxCoeff(), 1e-9);
}

// Sums of squared reading errors (reading minus the truth at its capture).
struct NoiseSums {
  double sq[4] = {0, 0, 0, 0};  // position, velocity, attitude, body rate: sums of squares
  int samples = 0;              // readings (each three axes)
  double StdDev(int k) const { return std::sqrt(sq[k] / (3.0 * samples)); }
};

// (c) Motion capture: each reading delivered no earlier than its capture + latency and no
// later than the step that reaches it, captures every 1 / rate_hz from t = 0, payload first
// then vehicle by vehicle, and each noise's standard deviation as declared. Over 2000 samples
// of three axes the sample standard deviation's own spread is about 1 %; 20 % is the brief's
// bound, which a wrong scale (a variance used as a deviation, a missing noise) fails.
TEST(TeamWorldTest, MocapArrivesAtItsRateAfterItsLatencyWithItsNoise) {
  const CooperativeTeam team = TestBar();
  TeamWorldConfig config = Config(team);
  config.mocap.rate_hz = 100.0;
  config.mocap.latency_s = 0.015;
  config.mocap.position_noise_m = 0.002;
  config.mocap.velocity_noise_mps = 0.03;
  config.mocap.attitude_noise_rad = 0.004;
  config.mocap.body_rate_noise_radps = 0.02;
  config.mocap.rate_gyro_noise_radps = 0.05;
  TeamWorld world(config);
  const CooperativeModel model(team);
  world.Reset(model.HangingState(Vector3d(0, 0, 1.5)));

  std::vector<VectorXd> truth_at_step = {world.GetTruth().x};
  NoiseSums payload, vehicles;
  double gyro_sq = 0.0;
  int gyro_samples = 0;
  std::vector<double> payload_captures;
  int expected_next_body = -1;
  constexpr int kCaptures = 2000;
  while (static_cast<int>(payload_captures.size()) < kCaptures) {
    world.Step();
    const TeamTruth t = world.GetTruth();
    truth_at_step.push_back(t.x);
    for (int i = 0; i < 2; ++i) {
      const Vector3d e = world.GyroSample_B(i) - t.x.segment<3>(I::Vehicle(i) + I::kVehicleRate);
      gyro_sq += e.squaredNorm();
      ++gyro_samples;
    }
    for (const BodyReading& r : world.TakeDelivered()) {
      // delivered once capture + latency has passed, within the step that reached it
      EXPECT_LE(r.capture_time_s + config.mocap.latency_s, world.time_s() + 1e-9);
      EXPECT_GT(r.capture_time_s + config.mocap.latency_s,
                world.time_s() - World::kPhysicsDt_s + 1e-9);
      EXPECT_EQ(r.body, expected_next_body);
      expected_next_body = r.body == 1 ? -1 : r.body + 1;
      if (r.body == -1) payload_captures.push_back(r.capture_time_s);

      const long step = std::lround(r.capture_time_s / World::kPhysicsDt_s);
      ASSERT_LT(step, static_cast<long>(truth_at_step.size()));
      const VectorXd& x = truth_at_step[static_cast<size_t>(step)];
      const int at = r.body < 0 ? 0 : I::Vehicle(r.body);
      const Eigen::Quaterniond q_true(x(at + 6), x(at + 7), x(at + 8), x(at + 9));
      const Eigen::AngleAxisd err(q_true.conjugate() * r.q_W);
      NoiseSums& sums = r.body < 0 ? payload : vehicles;
      sums.sq[0] += (r.p_W_m - x.segment<3>(at)).squaredNorm();
      sums.sq[1] += (r.v_W_mps - x.segment<3>(at + 3)).squaredNorm();
      sums.sq[2] += (err.angle() * err.axis()).squaredNorm();
      sums.sq[3] += (r.w_body_radps - x.segment<3>(at + 10)).squaredNorm();
      ++sums.samples;
    }
  }
  // captures every 10 steps from t = 0
  for (size_t k = 0; k < payload_captures.size(); ++k) {
    EXPECT_NEAR(payload_captures[k], k / config.mocap.rate_hz, 1e-9) << "capture " << k;
  }
  const double declared[4] = {config.mocap.position_noise_m, config.mocap.velocity_noise_mps,
                              config.mocap.attitude_noise_rad, config.mocap.body_rate_noise_radps};
  const char* names[4] = {"position", "velocity", "attitude", "body rate"};
  for (int k = 0; k < 4; ++k) {
    std::printf("[measured] mocap %s noise: payload %.4g, vehicles %.4g, declared %.4g\n", names[k],
                payload.StdDev(k), vehicles.StdDev(k), declared[k]);
    EXPECT_NEAR(payload.StdDev(k), declared[k], 0.2 * declared[k]) << names[k];
    EXPECT_NEAR(vehicles.StdDev(k), declared[k], 0.2 * declared[k]) << names[k];
  }
  const double gyro_std_radps = std::sqrt(gyro_sq / (3.0 * gyro_samples));
  EXPECT_NEAR(gyro_std_radps, config.mocap.rate_gyro_noise_radps,
              0.2 * config.mocap.rate_gyro_noise_radps);
  EXPECT_FALSE(world.Crash().crashed) << world.Crash().reason;
}

// (d) Vehicle 0 pushed into vehicle 1 (cables slack, the payload on the ground): the collision
// latches naming both, and later conditions do not replace it.
TEST(TeamWorldTest, VehiclesPushedTogetherCollide) {
  CooperativeTeam team = TestBar();
  TeamWorld world(Config(team));
  world.Reset(PayloadOnGround(team, 0.45));
  ASSERT_GT(world.MinVehicleSeparation_m(), 0.35);
  // vehicle 0 at +x, vehicle 1 at -x: 2 m/s towards vehicle 1
  world.AddVelocity(0, Vector3d(-2.0, 0, 0));
  for (int s = 0; s < 300 && !world.Crash().crashed; ++s) world.Step();
  const CrashStatus crash = world.Crash();
  ASSERT_TRUE(crash.crashed);
  EXPECT_EQ(crash.reason, "vehicle 0 and vehicle 1 collide");
  EXPECT_LT(world.MinVehicleSeparation_m(), 0.21);  // the boxes' full widths, 0.2 m
  for (int s = 0; s < 300; ++s) world.Step();
  EXPECT_EQ(world.Crash().reason, crash.reason);
  EXPECT_EQ(world.Crash().time_s, crash.time_s);
}

// A taut cable through another vehicle's rotor disc is a crash naming both (MuJoCo's tendons
// do not collide, so the world checks it); the same vehicle beside the cable, just beyond its
// rotors' reach, is not.
TEST(TeamWorldTest, ACableThroughAnotherVehiclesRotorsCrashes) {
  CooperativeTeam team = TestBar();
  team.vehicles[1].cable_length_m = 1.0;  // slack wherever vehicle 1 is placed below
  const CooperativeModel model(team);
  const VectorXd hanging = model.HangingState(Vector3d(0, 0, 1.0));
  const Vector3d p_vehicle0 = hanging.segment<3>(I::Vehicle(0));
  const Vector3d p_attach0 = hanging.head<3>() + team.vehicles[0].p_PA_P_m;
  const double reach_m = team.vehicles[1].params.arm_length_m + SingleSceneRotorRadius_m(
                                                                    DataPath("models/scene.xml"));
  for (const double offset_m : {0.0, reach_m - 0.01, reach_m + 0.01}) {
    // vehicle 1 level, halfway down vehicle 0's cable, offset_m from it across the bar
    VectorXd x0 = hanging;
    x0.segment<3>(I::Vehicle(1)) = 0.5 * (p_vehicle0 + p_attach0) + Vector3d(0, offset_m, 0);
    TeamWorld world(Config(team));
    world.Reset(x0);
    world.Step();
    if (offset_m < reach_m) {
      EXPECT_TRUE(world.Crash().crashed) << offset_m;
      EXPECT_EQ(world.Crash().reason, "cable 0 strikes vehicle 1's rotors") << offset_m;
    } else {
      EXPECT_FALSE(world.Crash().crashed) << world.Crash().reason;
    }
  }
}

// (e) A vehicle with its motors at their minimum falls onto the ground: the crash names it. The
// payload resting on the ground under hovering vehicles is not a crash.
TEST(TeamWorldTest, AVehicleOnTheGroundCrashesAPayloadOnTheGroundDoesNot) {
  const CooperativeTeam team = TestTriangle();
  {
    TeamWorld world(Config(team));
    world.Reset(PayloadOnGround(team, 0.45));
    for (int s = 0; s < 2000; ++s) world.Step();
    EXPECT_FALSE(world.Crash().crashed) << world.Crash().reason;
  }
  TeamWorld world(Config(team));
  world.Reset(PayloadOnGround(team, 0.3));
  world.SetMotorSpeedCommand(1, InputVector::Zero());  // clamped to the minimum
  for (int s = 0; s < 1000 && !world.Crash().crashed; ++s) world.Step();
  ASSERT_TRUE(world.Crash().crashed);
  EXPECT_EQ(world.Crash().reason, "vehicle 1 contact with ground");
}

// A vehicle falling onto the payload lying on the ground crashes naming it.
TEST(TeamWorldTest, AVehicleFallingOnThePayloadCrashes) {
  const CooperativeTeam team = TestBar();
  TeamWorld world(Config(team));
  VectorXd x0 = PayloadOnGround(team, 0.45);
  x0.segment<3>(I::Vehicle(0)) = Vector3d(0, 0, 0.2);  // above the payload's sphere
  world.Reset(x0);
  world.SetMotorSpeedCommand(0, InputVector::Zero());
  for (int s = 0; s < 1000 && !world.Crash().crashed; ++s) world.Step();
  ASSERT_TRUE(world.Crash().crashed);
  EXPECT_EQ(world.Crash().reason, "vehicle 0 contact with payload");
}

// A vehicle upside down, and a vehicle or the payload leaving the arena, crash naming the body.
TEST(TeamWorldTest, TiltAndArenaCrashesNameTheBody) {
  const CooperativeTeam team = TestBar();
  const CooperativeModel model(team);
  {
    TeamWorld world(Config(team));
    VectorXd x0 = model.HangingState(Vector3d(0, 0, 1.5));
    const Eigen::Quaterniond q(Eigen::AngleAxisd(2.0, Vector3d::UnitX()));  // 115 deg
    x0.segment<4>(I::Vehicle(1) + I::kVehicleQuat) << q.w(), q.x(), q.y(), q.z();
    world.Reset(x0);
    world.Step();
    EXPECT_EQ(world.Crash().reason, "vehicle 1 tilt > 90 deg");
  }
  {
    TeamWorld world(Config(team));
    world.Reset(model.HangingState(Vector3d(kArenaHalfWidth_m - 0.001 - 0.2, 0, 1.5)));
    world.AddVelocity(0, Vector3d(2.0, 0, 0));
    for (int s = 0; s < 100 && !world.Crash().crashed; ++s) world.Step();
    EXPECT_EQ(world.Crash().reason, "vehicle 0 left the 20x20x10 m arena");
  }
  {
    TeamWorld world(Config(team));
    world.Reset(model.HangingState(Vector3d(0, -kArenaHalfWidth_m + 0.001, 1.5)));
    world.AddVelocity(-1, Vector3d(0, -1.0, 0));
    for (int s = 0; s < 100 && !world.Crash().crashed; ++s) world.Step();
    EXPECT_EQ(world.Crash().reason, "payload left the 20x20x10 m arena");
  }
}

// An impulse is a constant force over its duration, as the single vehicle's World gives it: a
// sideways push of J over 50 ms on the hanging payload has given it a fiftieth of J / m after
// one step and J / m by its end. The cables' pull across the push over 50 ms (a 5 mm swing on
// 0.5 m cables: tension times 0.01) bounds the error at 5 % of J / m; measured about 1 %.
TEST(TeamWorldTest, AnImpulseIsSpreadOverItsDuration) {
  const CooperativeTeam team = TestBar();
  TeamWorld world(Config(team));
  world.Reset(CooperativeModel(team).HangingState(Vector3d(0, 0, 1.5)));
  for (int s = 0; s < 100; ++s) world.Step();
  const double dv_mps = 0.2;  // J / m
  const double v0_mps = world.GetTruth().x(I::kPayloadVel);
  world.ApplyImpulse(-1, Vector3d(dv_mps * team.payload_mass_kg, 0, 0), 0.05);
  world.Step();
  EXPECT_NEAR(world.GetTruth().x(I::kPayloadVel) - v0_mps, dv_mps / 50.0, 0.05 * dv_mps / 50.0);
  for (int s = 1; s < 50; ++s) world.Step();
  EXPECT_NEAR(world.GetTruth().x(I::kPayloadVel) - v0_mps, dv_mps, 0.05 * dv_mps);
  // over: no more force after the duration
  const double v_end_mps = world.GetTruth().x(I::kPayloadVel);
  world.Step();
  EXPECT_LT(world.GetTruth().x(I::kPayloadVel), v_end_mps);
  EXPECT_THROW(world.ApplyImpulse(3, Vector3d::Zero(), 0.01), std::out_of_range);
  EXPECT_THROW(world.ApplyImpulse(-1, Vector3d(NAN, 0, 0), 0.01), std::invalid_argument);
  EXPECT_THROW(world.AddVelocity(-1, Vector3d(0, INFINITY, 0)), std::invalid_argument);
}

// (f) An upward impulse on the payload lifts it towards the vehicles: its cables go slack, and
// taut again once it falls back.
TEST(TeamWorldTest, UpwardImpulseOnThePayloadSlacksItsCablesBriefly) {
  const CooperativeTeam team = TestBar();
  TeamWorld world(Config(team));
  world.Reset(CooperativeModel(team).HangingState(Vector3d(0, 0, 1.5)));
  for (int s = 0; s < 200; ++s) world.Step();
  const double v_before_mps = world.GetTruth().x(I::kPayloadVel + 2);
  world.AddVelocity(-1, Vector3d(0, 0, 1.0));
  EXPECT_NEAR(world.GetTruth().x(I::kPayloadVel + 2) - v_before_mps, 1.0, 1e-12);
  bool went_slack = false, taut_again = false;
  for (int s = 0; s < 500; ++s) {
    world.Step();
    const TeamTruth t = world.GetTruth();
    bool all_taut = true;
    for (CableMode mode : t.modes) all_taut &= mode == CableMode::kTaut;
    if (!all_taut) went_slack = true;
    if (went_slack && all_taut) taut_again = true;
  }
  EXPECT_TRUE(went_slack);
  EXPECT_TRUE(taut_again);
  EXPECT_FALSE(world.Crash().crashed) << world.Crash().reason;
}

// Everything a run of 1000 steps produced.
struct RunRecord {
  VectorXd x;
  std::vector<BodyReading> readings;
  std::vector<Vector3d> gyro;
};

RunRecord RunThousandSteps(TeamWorld* world) {
  RunRecord r;
  world->Reset(CooperativeModel(world->team()).HangingState(Vector3d(0, 0, 1.5)));
  InputVector w = world->GetTruth().motor_speed_radps.segment<4>(0);
  world->SetMotorSpeedCommand(0, w * 1.01);
  for (int s = 0; s < 1000; ++s) {
    world->Step();
    for (const BodyReading& b : world->TakeDelivered()) r.readings.push_back(b);
    for (int i = 0; i < world->VehicleCount(); ++i) r.gyro.push_back(world->GyroSample_B(i));
  }
  r.x = world->GetTruth().x;
  return r;
}

bool SameReadings(const RunRecord& a, const RunRecord& b) {
  if (a.readings.size() != b.readings.size()) return false;
  for (size_t k = 0; k < a.readings.size(); ++k) {
    const BodyReading &p = a.readings[k], &q = b.readings[k];
    if (p.body != q.body || p.capture_time_s != q.capture_time_s || p.p_W_m != q.p_W_m ||
        p.v_W_mps != q.v_W_mps || p.q_W.coeffs() != q.q_W.coeffs() ||
        p.w_body_radps != q.w_body_radps) {
      return false;
    }
  }
  return a.gyro == b.gyro;
}

// (g) One seed, one run: two worlds of the same seed agree bit for bit, a Reset world replays
// its noise, and another seed draws other noise on the same physics.
TEST(TeamWorldTest, SameSeedSameRunOtherSeedOtherNoise) {
  const CooperativeTeam team = TestTriangle();
  TeamWorld a(Config(team, 7)), b(Config(team, 7)), c(Config(team, 8));
  const RunRecord ra = RunThousandSteps(&a), rb = RunThousandSteps(&b);
  const RunRecord rc = RunThousandSteps(&c), ra2 = RunThousandSteps(&a);
  EXPECT_EQ(ra.x, rb.x);
  EXPECT_TRUE(SameReadings(ra, rb));
  EXPECT_EQ(ra.x, ra2.x);
  EXPECT_TRUE(SameReadings(ra, ra2));
  EXPECT_EQ(ra.x, rc.x);  // noise does not reach the physics
  ASSERT_EQ(ra.readings.size(), rc.readings.size());
  EXPECT_FALSE(SameReadings(ra, rc));
  EXPECT_NE(ra.readings.back().p_W_m, rc.readings.back().p_W_m);
}

// (h) Bad teams and settings are input errors that name what is wrong.
void ExpectInputError(const TeamWorldConfig& config, const std::string& names) {
  try {
    TeamWorld world(config);
    ADD_FAILURE() << "no error for " << names;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(names), std::string::npos) << e.what();
  }
}

TEST(TeamWorldTest, BadInputIsNamed) {
  TeamWorldConfig config = Config(TestBar());
  config.team.vehicles.clear();
  ExpectInputError(config, "team.vehicles");

  config = Config(TestTeam(4, 0.3, Vector3d(3e-3, 3e-3, 6e-3), 0.2));
  ExpectInputError(config, "team.vehicles");

  config = Config(TestBar());
  config.team.vehicles[1].cable_length_m = 0.0;
  ExpectInputError(config, "team.vehicles[1].cable_length_m");
  config.team.vehicles[1].cable_length_m = -0.5;
  ExpectInputError(config, "team.vehicles[1].cable_length_m");

  config = Config(TestBar());
  config.team.payload_mass_kg = 0.0;
  ExpectInputError(config, "team.payload_mass_kg");

  config = Config(TestBar());
  config.team.vehicles[0].params.quad_mass_kg = -1.0;
  ExpectInputError(config, "team.vehicles[0].params.quad_mass_kg");

  config = Config(TestBar());
  config.mocap.rate_hz = 300.0;  // not a whole number of 1 ms steps
  ExpectInputError(config, "mocap.rate_hz");

  config = Config(TestBar());
  config.scene_path = "/nonexistent/scene.xml";
  ExpectInputError(config, "/nonexistent/scene.xml");

  // a state of the wrong size, a command to a vehicle the team does not have
  TeamWorld world(Config(TestBar()));
  EXPECT_THROW(world.Reset(VectorXd::Zero(13)), std::invalid_argument);
  EXPECT_THROW(world.SetMotorSpeedCommand(2, InputVector::Zero()), std::out_of_range);
  EXPECT_THROW(world.SetMotorSpeedCommand(0, InputVector::Constant(NAN)), std::invalid_argument);
}

}  // namespace
}  // namespace hpa::sim
