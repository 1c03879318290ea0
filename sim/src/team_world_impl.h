#pragma once
// TeamWorld's state and the steps its source files share (team_world.cc: the public API and the
// step order; team_world_scene.cc: the scene and its ids; team_world_sensors.cc: motion capture,
// the gyros and the onboard sensors; team_world_crash.cc: warnings and crash checks).

#include <mujoco/mujoco.h>

#include <Eigen/Dense>
#include <array>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "hpa/models/lockstep.h"
#include "hpa/sim/disturbances.h"
#include "hpa/sim/faults.h"
#include "hpa/sim/sensor_suite.h"
#include "hpa/sim/team_world.h"
#include "hpa/sim/vehicle.h"

namespace hpa::sim {

/// Throws hpa::InputError naming the field of a team or a motion-capture setting that cannot be
/// simulated (team_world.h's constructor lists them).
void ValidateTeamConfig(const TeamWorldConfig& config);

/// Name of a body in crash reasons: "payload" or "vehicle i".
std::string TeamBodyName(int body);

/// What a TeamWorld holds: MuJoCo's model and data, the ids it drives, each vehicle's components
/// and the team's sensors.
struct TeamWorld::Impl {
  // where a free body's state lives in MuJoCo
  struct FreeBody {
    int body = -1;  // body id
    int qpos = -1;  // first qpos of its free joint [p, q]
    int dof = -1;   // first dof of its free joint [v (world), w (body)]
  };

  TeamWorldConfig config;
  int n = 0;                   // vehicles
  int mocap_period_steps = 1;  // physics steps between two motion-capture samples
  mjModel* m = nullptr;
  mjData* d = nullptr;
  std::string scene_xml;                   // the MJCF m was compiled from
  std::unique_ptr<TeamRenderer> renderer;  // the video's cameras, made on first use

  FreeBody payload;
  std::vector<FreeBody> vehicles;                  // (n)
  std::vector<std::array<int, 4>> rotor_actuator;  // each vehicle's rotors' actuators (n)
  std::vector<int> box_geom;                       // each vehicle's collision box (n)
  std::vector<int> tension_adr;                    // each cable's tension sensor (n)
  int payload_geom = -1, ground_geom = -1;
  double rotor_radius_m = 0.0;    // the single scene's rotor disc: a rotor's reach beyond its axis
  double payload_radius_m = 0.0;  // the payload's sphere in the scene (its drag)

  int64_t step = 0;
  std::mt19937_64 rng;  // the motion capture's and the simple gyros' noise
  std::normal_distribution<double> normal{0.0, 1.0};
  // each vehicle's faults (its motors and onboard sensors read them) and its motors and rotors,
  // the single World's components bound to its rotors (n each)
  std::vector<std::unique_ptr<Faults>> faults;
  std::vector<Vehicle> actuation;
  // each vehicle's rotors' thrust and torque factors, the profile's actuation draw  (n each)
  std::vector<Eigen::Vector4d> rotor_kf_draw, rotor_km_draw;
  double t0_s = 0.0;                          // a team's clock starts at 0 at every Reset
  std::vector<Eigen::Vector3d> gyro_B_radps;  // this step's gyro samples (n x 3)
  DelayLine<BodyReading> mocap_line{0.0};     // readings waiting for their latency
  std::optional<Disturbances> disturbances;   // pushes, wind and drag on every body
  // each vehicle's onboard sensors (n; none without config.onboard_sensors)
  std::vector<std::unique_ptr<SensorSuite>> onboard;
  std::vector<SystemState> onboard_state;  // each vehicle's sensed state at the step's start (n)
  CrashStatus crash;
  std::vector<int> warning_count;  // per MuJoCo warning kind (mjNWARNING)

  double time_s() const { return static_cast<double>(step) * World::kPhysicsDt_s; }
  const Params& params(int i) const { return config.team.vehicles[i].params; }

  // three independent standard normal draws
  Eigen::Vector3d Normal3() {
    const double a = normal(rng);
    const double b = normal(rng);
    const double c = normal(rng);
    return Eigen::Vector3d(a, b, c);
  }

  // [p, v, q (w,x,y,z), w_body] of a free body (13)
  Eigen::Matrix<double, 13, 1> Block(const FreeBody& b) const {
    Eigen::Matrix<double, 13, 1> x;
    for (int k = 0; k < 3; ++k) {
      x(k) = d->qpos[b.qpos + k];
      x(3 + k) = d->qvel[b.dof + k];
      x(10 + k) = d->qvel[b.dof + 3 + k];
    }
    for (int k = 0; k < 4; ++k) x(6 + k) = d->qpos[b.qpos + 3 + k];
    return x;
  }

  // writes x's block at `at` into the free body's qpos and qvel (angular velocity in the body
  // frame in both), its quaternion normalised
  void SetBlock(const FreeBody& b, const Eigen::VectorXd& x, int at) {
    const Eigen::Vector4d q = x.segment<4>(at + 6).normalized();
    for (int k = 0; k < 3; ++k) {
      d->qpos[b.qpos + k] = x(at + k);
      d->qvel[b.dof + k] = x(at + 3 + k);
      d->qvel[b.dof + 3 + k] = x(at + 10 + k);
    }
    for (int k = 0; k < 4; ++k) d->qpos[b.qpos + 3 + k] = q(k);
  }

  const FreeBody& Body(int body) const { return body < 0 ? payload : vehicles[body]; }

  // attachment point i in the world (m)
  Eigen::Vector3d AttachPoint_W(int i) const {
    const Eigen::Matrix<double, 13, 1> xp = Block(payload);
    const Eigen::Quaterniond q_WP(xp(6), xp(7), xp(8), xp(9));
    return xp.head<3>() + q_WP.normalized() * config.team.vehicles[i].p_PA_P_m;
  }

  // vehicle i's distance to its attachment point (m)
  double CableLength_m(int i) const {
    return (AttachPoint_W(i) - Block(vehicles[i]).head<3>()).norm();
  }

  bool Taut(int i) const {
    return CableLength_m(i) >=
           config.team.vehicles[i].cable_length_m - World::kTautLengthTolerance_m;
  }

  // a vehicle index in 0 .. n-1, else std::out_of_range naming the caller
  void RequireVehicle(int vehicle, const char* caller) const;

  // team_world_scene.cc: the scene built and loaded into m and d, its ids resolved
  void LoadScene();
  void ResolveIds();
  // team_world.cc: each vehicle's motors and faults, the disturbances, bound to the scene
  void BindComponents();
  // each vehicle's rotor speeds holding its weight and its taut cable's static share
  std::vector<InputVector> HoldingSpeeds_radps() const;

  // team_world_sensors.cc
  void MakeOnboardSensors();
  void SampleGyros();
  void SampleMocap();
  // each vehicle's state as its onboard sensors see it, at the start of a step
  void CaptureOnboardState();
  // each vehicle's onboard sensors on the step just taken
  void SampleOnboard();

  // team_world_crash.cc
  void CheckWarnings();
  void LatchCrash(const std::string& reason);
  int VehicleOfGeom(int g) const;
  void CheckCrash();
  void CheckCableStrikes();
};

}  // namespace hpa::sim
