#pragma once
// Test harness of the estimator tests: a hovering vehicle whose payload is kicked up, simulated by
// the analytic hybrid model with its sensors, and the estimator's errors on it (RunStats).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <memory>
#include <random>
#include <string>

#include "hpa/estimator/estimator.h"
#include "hpa/estimator/estimator_registry.h"
#include "hpa/models/camera_model.h"
#include "hpa/models/hybrid_model.h"
#include "hpa/models/rotor_model.h"
#include "hpa/sim/analytic_camera.h"

namespace hpa {
namespace testing_util {

// Truth from the analytic hybrid model (level quadrotor at hover thrust), with a payload kick
// at kick_time_s: slack free flight, and an inelastic re-taut (docs/design.md section 4) when the
// cable reaches l again. Sensors: IMU 500 Hz, VIO 30 Hz (20 ms late), analytic camera 30 Hz
// (one frame late), all noisy from one seeded generator.
struct RunStats {
  double taut_payload_rmse_m = 0.0;       // payload error while truly taut (after 0.5 s)
  double slack_payload_rmse_m = 0.0;      // payload error while truly slack (after detection)
  double max_length_error_m = 0.0;        // | |p_L - p_Q| estimated - l | while estimated taut
  double any_slack_payload_rmse_m = 0.0;  // payload error while truly slack, any estimated mode
  double slack_latency_s = -1.0;          // true slack start -> estimated slack
  int false_slack_steps = 0;              // estimated slack while truly taut (before the kick)
  bool ever_slack = false;
  // mean payload velocity error from kRetautWindowStart_s to kRetautWindow_s after the true
  // re-taut (0: no re-taut)
  double retaut_payload_velocity_error_mps = 0.0;
  EstimatorHealth health;  // at the end of the run
};

// Window after a true re-taut over which the payload velocity error is averaged: from the
// detection that restarts the cable filter (a frame and its latency after the snap) to a few
// frames later, where the velocity row, fused at the next detection, acts.
constexpr double kRetautWindow_s = 0.12;
constexpr double kRetautWindowStart_s = 0.05;

// Sums of squared payload errors (and of velocity errors after the re-taut) with their counts,
// for RunStats' RMS and mean values.
struct ErrorSums {
  double taut_se = 0, slack_se = 0, any_slack_se = 0, retaut_dv = 0;
  int taut_n = 0, slack_n = 0, any_slack_n = 0, retaut_n = 0;
};

// RunStats' RMS payload errors and mean re-taut velocity error from the sums (0 when empty).
inline void SetErrorStats(const ErrorSums& sums, RunStats* stats) {
  stats->retaut_payload_velocity_error_mps = sums.retaut_dv / std::max(1, sums.retaut_n);
  stats->taut_payload_rmse_m = std::sqrt(sums.taut_se / std::max(1, sums.taut_n));
  stats->slack_payload_rmse_m = std::sqrt(sums.slack_se / std::max(1, sums.slack_n));
  stats->any_slack_payload_rmse_m = std::sqrt(sums.any_slack_se / std::max(1, sums.any_slack_n));
}

// The inelastic re-taut of docs/design.md section 4 on the truth: the relative velocity along
// the cable removed (momentum kept), the payload put on the cable's sphere. Returns the
// quadrotor's velocity change, which the IMU feels as a jerk.
inline Eigen::Vector3d Retaut(const Params& p, const Eigen::Vector3d& d, SystemState* truth) {
  const Eigen::Vector3d xi = d.normalized();
  const double m = p.quad_mass_kg, m_L = p.payload_mass_kg;
  const double v_c = (m * truth->v_WQ_W.dot(xi) + m_L * truth->v_WL_W.dot(xi)) / (m + m_L);
  const Eigen::Vector3d collision_dv_W = (v_c - truth->v_WQ_W.dot(xi)) * xi;
  truth->v_WQ_W += collision_dv_W;
  truth->v_WL_W += (v_c - truth->v_WL_W.dot(xi)) * xi;
  truth->p_WL_W = truth->p_WQ_W + p.cable_length_m * xi;
  return collision_dv_W;
}

// The IMU sample at time t: the true body rate and specific force R^T (a_Q + g e3), the
// re-taut's velocity change (collision_dv_W) felt over the step dt_s, with gyro and accelerometer
// noise from noise3 (in that order).
template <typename Noise>
inline ImuSample SimulatedImu(const Params& p, double t, double dt_s, const SystemState& truth,
                              const StateVector& x_dot, const Eigen::Vector3d& collision_dv_W,
                              Noise& noise3) {
  const Eigen::Matrix3d R_WB = truth.q_WB.toRotationMatrix();
  ImuSample imu;
  imu.time_s = t;
  imu.gyro_B_radps = truth.w_B + noise3(2.4e-4 / std::sqrt(dt_s));
  imu.accel_B_mps2 =
      R_WB.transpose() * (x_dot.segment<3>(StateIndex::kQuadVel) + collision_dv_W / dt_s +
                          Eigen::Vector3d(0, 0, p.gravity_mps2)) +
      noise3(1.7e-3 / std::sqrt(dt_s));
  return imu;
}

// The VIO sample at time t: true position and velocity with noise from noise3, true attitude.
template <typename Noise>
inline VioSample SimulatedVio(double t, const SystemState& truth, Noise& noise3) {
  VioSample vio;
  vio.time_s = t;
  vio.p_WB_W = truth.p_WQ_W + noise3(0.01);
  vio.q_WB = truth.q_WB;
  vio.v_WB_W = truth.v_WQ_W + noise3(0.02);
  return vio;
}

// Scores one estimate at time t against the truth (mode: the true mode, truly_slack: the cable
// shorter than its length; slack_start_s and retaut_time_s are negative until they happen).
inline void ScoreEstimate(const Params& p, double t, const SystemState& est,
                          const SystemState& truth, CableMode mode, bool truly_slack,
                          double slack_start_s, double retaut_time_s, RunStats* stats,
                          ErrorSums* sums) {
  const double e2 = (est.p_WL_W - truth.p_WL_W).squaredNorm();
  if (est.mode == CableMode::kSlack) {
    stats->ever_slack = true;
    if (stats->slack_latency_s < 0 && slack_start_s >= 0)
      stats->slack_latency_s = t - slack_start_s;
    if (!truly_slack && slack_start_s < 0) ++stats->false_slack_steps;
  } else {
    stats->max_length_error_m = std::max(
        stats->max_length_error_m, std::abs((est.p_WL_W - est.p_WQ_W).norm() - p.cable_length_m));
  }
  if (t > 0.5 && mode == CableMode::kTaut && !truly_slack) {
    sums->taut_se += e2;
    ++sums->taut_n;
  }
  if (truly_slack && est.mode == CableMode::kSlack) {
    sums->slack_se += e2;
    ++sums->slack_n;
  }
  if (truly_slack) {
    sums->any_slack_se += e2;
    ++sums->any_slack_n;
  }
  if (retaut_time_s >= 0 && t > retaut_time_s + kRetautWindowStart_s &&
      t <= retaut_time_s + kRetautWindow_s) {
    sums->retaut_dv += (est.v_WL_W - truth.v_WL_W).norm();
    ++sums->retaut_n;
  }
}

// told_thrust_scale: the estimator is told the thrust the rotors make times this (1: what the
// allocation produced; above 1: a command a saturated mixer did not deliver).
inline RunStats Simulate(const std::string& variant, double kick_up_mps, uint64_t seed,
                         const EstimatorConfig& config = EstimatorConfig{},
                         double told_thrust_scale = 1.0, double tilt_rad = 0.0) {
  const Params p;
  const HybridModel model(p);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  auto noise3 = [&](double std_dev) -> Eigen::Vector3d {
    return Eigen::Vector3d(n01(rng), n01(rng), n01(rng)) * std_dev;
  };

  SystemState truth;
  truth.p_WQ_W = Eigen::Vector3d(0, 0, 1.5);
  truth.p_WL_W = truth.p_WQ_W - Eigen::Vector3d(0, 0, p.cable_length_m);
  // a tilted vehicle (rolled about x, no body rate) accelerates sideways and swings the payload
  truth.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(tilt_rad, Eigen::Vector3d::UnitX()));
  StateVector x = truth.ToVector();
  const InputVector u = InputVector::Constant(p.HoverMotorSpeedRadps());
  const double thrust_N = WrenchFromRotorSpeeds(p, u)(0);

  std::unique_ptr<Estimator> estimator = MakeEstimator(variant, config, p, truth);
  estimator->OnAllocatedThrust(told_thrust_scale * thrust_N);
  const sim::AnalyticCamera camera(p);

  constexpr double kDt = 0.002;
  const double kick_time_s = 1.0;
  CableMode mode = CableMode::kTaut;
  double slack_start_s = -1.0;
  std::deque<VioSample> vio_queue;
  std::deque<PayloadDetection> camera_queue;
  RunStats stats;
  ErrorSums sums;
  double retaut_time_s = -1.0;
  for (int k = 1; k <= 1250; ++k) {  // 2.5 s
    const double t = k * kDt;
    // truth step, kick and re-taut
    StateVector x_dot = model.Derivative(x, u, mode);
    x = model.Step(x, u, mode, kDt);
    if (kick_up_mps > 0 && std::abs(t - kick_time_s) < 0.5 * kDt) {
      x(StateIndex::kPayloadVel + 2) += kick_up_mps;
      mode = CableMode::kSlack;
    }
    truth.FromVector(x);
    const Eigen::Vector3d d = truth.p_WL_W - truth.p_WQ_W;
    Eigen::Vector3d collision_dv_W = Eigen::Vector3d::Zero();  // the IMU feels the jerk
    if (mode == CableMode::kSlack && d.norm() >= p.cable_length_m &&
        (truth.v_WL_W - truth.v_WQ_W).dot(d) > 0) {
      collision_dv_W = Retaut(p, d, &truth);
      x = truth.ToVector();
      mode = CableMode::kTaut;
      if (retaut_time_s < 0) retaut_time_s = t;
    }
    const bool truly_slack = d.norm() < p.cable_length_m - p.slack_epsilon_m;
    if (truly_slack && slack_start_s < 0) slack_start_s = t;

    estimator->OnImu(SimulatedImu(p, t, kDt, truth, x_dot, collision_dv_W, noise3));
    // 30 Hz VIO and camera (every 17th IMU step), delivered late
    if (k % 17 == 0) {
      vio_queue.push_back(SimulatedVio(t, truth, noise3));
      for (const PayloadDetection& det : camera_queue) estimator->OnPayloadDetection(det);
      camera_queue.clear();
      camera_queue.push_back(camera.Measure(PayloadInCamera_C(p, truth), t, rng));
    }
    while (!vio_queue.empty() && vio_queue.front().time_s + 0.02 <= t + 1e-9) {
      estimator->OnVio(vio_queue.front());
      vio_queue.pop_front();
    }

    // score
    const SystemState est = estimator->Estimate(t);
    EXPECT_TRUE(est.AllFinite());
    if (std::getenv("EST_DEBUG") && k % 10 == 0) {
      std::printf("t %.3f truth %s est %s len %.3f err %.1f mm ez %.1f\n", t, ToString(mode),
                  ToString(est.mode), d.norm(), 1e3 * (est.p_WL_W - truth.p_WL_W).norm(),
                  1e3 * (est.p_WL_W - truth.p_WL_W).z());
    }
    ScoreEstimate(p, t, est, truth, mode, truly_slack, slack_start_s, retaut_time_s, &stats, &sums);
  }
  SetErrorStats(sums, &stats);
  stats.health = estimator->Health();
  return stats;
}

}  // namespace testing_util
}  // namespace hpa
