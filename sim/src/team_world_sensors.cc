// TeamWorld's sensors: the team's motion capture, each vehicle's simple gyro, and each vehicle's
// onboard sensors (the single vehicle's IMU, VIO and rate gyro, through a SensorSuite).

#include <mujoco/mujoco.h>

#include <Eigen/Geometry>

#include "hpa/models/seed_streams.h"
#include "specific_force.h"
#include "team_world_impl.h"

namespace hpa::sim {

namespace {

// A small rotation of rotation vector r (rad) as a quaternion.
Eigen::Quaterniond RotationOf(const Eigen::Vector3d& r_rad) {
  const double angle_rad = r_rad.norm();
  if (angle_rad == 0.0) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle_rad, r_rad / angle_rad));
}

// The single vehicle's world configuration vehicle i's onboard sensors are made from: its params,
// the team's noise, rates and profile, and its own seed.
WorldConfig OnboardConfig(const TeamWorldConfig& team, int i) {
  WorldConfig c;
  c.params = team.team.vehicles[static_cast<size_t>(i)].params;
  c.scene_path = team.scene_path;
  c.seed = DeriveVehicleSeed(team.seed, SeedStream::kOnboardSensors, i);
  c.noise = team.noise;
  c.rates = team.rates;
  c.profile = team.profile;
  return c;
}

}  // namespace

// each vehicle's gyro: its true body rate plus white noise
void TeamWorld::Impl::SampleGyros() {
  for (int i = 0; i < n; ++i) {
    gyro_B_radps[i] =
        Block(vehicles[i]).segment<3>(10) + config.mocap.rate_gyro_noise_radps * Normal3();
  }
}

// the motion-capture readings of this step, if one is due: payload, then each vehicle
void TeamWorld::Impl::SampleMocap() {
  if (step % mocap_period_steps != 0) return;
  const MocapConfig& c = config.mocap;
  for (int body = -1; body < n; ++body) {
    const Eigen::Matrix<double, 13, 1> x = Block(Body(body));
    BodyReading r;
    r.body = body;
    r.capture_time_s = time_s();
    r.p_W_m = x.head<3>() + c.position_noise_m * Normal3();
    r.v_W_mps = x.segment<3>(3) + c.velocity_noise_mps * Normal3();
    const Eigen::Quaterniond q_true(x(6), x(7), x(8), x(9));
    r.q_W = (q_true.normalized() * RotationOf(c.attitude_noise_rad * Normal3())).normalized();
    r.w_body_radps = x.segment<3>(10) + c.body_rate_noise_radps * Normal3();
    mocap_line.Push(r.capture_time_s, r);
  }
  // a bound if the caller never takes them: 10 s of readings at 100 Hz
  const size_t max_queued = static_cast<size_t>(1000 * (n + 1));
  while (mocap_line.size() > max_queued) mocap_line.DropOldest();
}

void TeamWorld::Impl::MakeOnboardSensors() {
  if (!config.onboard_sensors) return;
  for (int i = 0; i < n; ++i)
    onboard.push_back(std::make_unique<SensorSuite>(OnboardConfig(config, i)));
  onboard_state.assign(static_cast<size_t>(n), SystemState());
}

void TeamWorld::Impl::CaptureOnboardState() {
  const Eigen::Matrix<double, 13, 1> xp = Block(payload);
  const Eigen::Quaterniond q_WP = Eigen::Quaterniond(xp(6), xp(7), xp(8), xp(9)).normalized();
  for (int i = 0; i < n; ++i) {
    // the vehicle as the quadrotor, its cable's attachment point as the payload
    const Eigen::Matrix<double, 13, 1> x = Block(vehicles[i]);
    const Eigen::Vector3d& p_PA_P = config.team.vehicles[static_cast<size_t>(i)].p_PA_P_m;
    SystemState& s = onboard_state[static_cast<size_t>(i)];
    s.time_s = time_s();
    s.p_WQ_W = x.head<3>();
    s.v_WQ_W = x.segment<3>(3);
    s.q_WB = Eigen::Quaterniond(x(6), x(7), x(8), x(9));
    s.w_B = x.segment<3>(10);
    s.p_WL_W = xp.head<3>() + q_WP * p_PA_P;
    // the payload's rate is in its body frame (free joint)
    s.v_WL_W = xp.segment<3>(3) + q_WP * Eigen::Vector3d(xp.segment<3>(10).cross(p_PA_P));
    s.mode = Taut(i) ? CableMode::kTaut : CableMode::kSlack;
    s.payload_visible = true;
    s.payload_supported = false;
  }
}

void TeamWorld::Impl::SampleOnboard() {
  // stamped with t_k (qacc from mj_step2 is the acceleration at t_k), as World::Step samples
  const Eigen::Vector3d gravity_W_mps2(m->opt.gravity[0], m->opt.gravity[1], m->opt.gravity[2]);
  SensorInput in;
  in.t_k_s = t0_s + static_cast<double>(step - 1) * World::kPhysicsDt_s;
  for (int i = 0; i < n; ++i) {
    const SystemState& s = onboard_state[static_cast<size_t>(i)];
    in.state = &s;
    in.specific_force_B_mps2 = SpecificForce_B(d, vehicles[i].dof, s.q_WB, gravity_W_mps2);
    onboard[static_cast<size_t>(i)]->Sample(in);
  }
}

}  // namespace hpa::sim
