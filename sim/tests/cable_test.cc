// The cable (a length-limited tendon, models/scene.xml) against its two requirements:
// a taut cable barely stretches at hover, and the slack-to-taut snap is the perfectly inelastic
// collision along the cable of docs/design.md section 4, with no rebound.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "hpa/models/params.h"
#include "hpa/sim/world.h"
#include "sim/tests/default_world_config.h"

namespace hpa::sim {
namespace {

TEST(CableTest, StretchAtHoverIsBelowFiveMillimetres) {
  World world(DefaultConfig());
  const Params& p = world.world_params();
  // default Reset: hovering, payload hanging, motors at the hover speed of quad + payload
  double max_stretch_m = 0.0, sum_tension_N = 0.0;
  int n = 0;
  for (int k = 0; k < 1000; ++k) {
    world.Step();
    const Truth t = world.GetTruth();
    if (k >= 500) {
      max_stretch_m = std::max(max_stretch_m, t.cable_length_m - p.cable_length_m);
      sum_tension_N += t.cable_tension_N;
      ++n;
    }
    ASSERT_EQ(t.state.mode, CableMode::kTaut) << "t = " << t.state.time_s;
  }
  const double mean_tension_N = sum_tension_N / n;
  std::printf("[measured] hover stretch %.3g mm, tension %.4f N (m_L g = %.4f N)\n",
              1e3 * max_stretch_m, mean_tension_N, p.payload_mass_kg * p.gravity_mps2);
  // requirement (task spec): taut stretch < 5 mm at hover (measured 0.04 mm)
  EXPECT_LT(max_stretch_m, 0.005);
  EXPECT_GT(max_stretch_m, 0.0) << "a limit constraint that never stretches is not engaged";
  // static tension = payload weight; 1e-3 relative: the quad drifts a hair in 1 s (measured 2e-5)
  EXPECT_NEAR(mean_tension_N, p.payload_mass_kg * p.gravity_mps2, 1e-3);
}

// One re-taut event, from a slack start until `window_s` after the cable first pulls.
struct RetautResult {
  Eigen::Vector3d v_Q_post, v_L_post;            // measured (3)
  Eigen::Vector3d v_Q_predicted, v_L_predicted;  // inelastic collision + external impulses (3)
  double jump_mps = 0;                           // |v_L jump along xi| predicted
  double min_length_after_m = 1e9;               // min cable length after the snap
  double peak_tension_N = 0;
  double max_separating_vel_mps = 0;  // max (v_L - v_Q).xi after the window: rebound if < 0
};

RetautResult RunRetaut(const StateVector& x0, double window_s, double watch_s) {
  World world(DefaultConfig());
  const Params& p = world.world_params();
  const double m = p.quad_mass_kg, m_L = p.payload_mass_kg;
  // motors held at the speed that carries the quadrotor alone: it hovers while the cable is slack
  const double w_quad = std::sqrt(m * p.gravity_mps2 / (4 * p.k_f_N_per_radps2));
  world.SetState(x0, InputVector::Constant(w_quad));

  // step while the cable is slack, remember the last slack state
  Truth pre = world.GetTruth();
  for (int k = 0; k < 2000 && world.GetTruth().cable_tension_N == 0.0; ++k) {
    pre = world.GetTruth();
    world.Step();
  }
  EXPECT_GT(world.GetTruth().cable_tension_N, 0.0) << "cable never went taut";

  // through the impact window (counted from the last slack state)
  RetautResult r;
  r.peak_tension_N = world.GetTruth().cable_tension_N;
  const int window_steps = static_cast<int>(std::lround(window_s / World::kPhysicsDt_s)) - 1;
  for (int k = 0; k < window_steps; ++k) {
    world.Step();
    r.peak_tension_N = std::max(r.peak_tension_N, world.GetTruth().cable_tension_N);
  }
  const Truth post = world.GetTruth();
  r.v_Q_post = post.state.v_WQ_W;
  r.v_L_post = post.state.v_WL_W;

  // prediction: each body's free drift over the window (gravity; thrust = quad weight, level),
  // then the inelastic collision along xi at the window's end
  const double t_w = post.state.time_s - pre.state.time_s;
  const Eigen::Vector3d g(0, 0, -p.gravity_mps2);
  const Eigen::Vector3d v_Q = pre.state.v_WQ_W;  // thrust cancels the quadrotor's weight
  const Eigen::Vector3d v_L = pre.state.v_WL_W + g * t_w;
  const Eigen::Vector3d xi = (post.state.p_WL_W - post.state.p_WQ_W).normalized();
  const double v_c = (m * v_Q.dot(xi) + m_L * v_L.dot(xi)) / (m + m_L);
  r.v_Q_predicted = v_Q + (v_c - v_Q.dot(xi)) * xi;
  r.v_L_predicted = v_L + (v_c - v_L.dot(xi)) * xi;
  r.jump_mps = std::abs(v_c - v_L.dot(xi));

  // afterwards: does the payload bounce back (cable slack again)?
  const int watch_steps = static_cast<int>(std::lround(watch_s / World::kPhysicsDt_s));
  r.max_separating_vel_mps = -1e9;
  for (int k = 0; k < watch_steps; ++k) {
    world.Step();
    const Truth t = world.GetTruth();
    r.min_length_after_m = std::min(r.min_length_after_m, t.cable_length_m);
    const Eigen::Vector3d xi_t = (t.state.p_WL_W - t.state.p_WQ_W).normalized();
    r.max_separating_vel_mps =
        std::max(r.max_separating_vel_mps, -(t.state.v_WL_W - t.state.v_WQ_W).dot(xi_t));
  }
  return r;
}

void Print(const char* name, const RetautResult& r) {
  std::printf(
      "[measured] %s: jump %.3f m/s, |dv_Q| err %.4f m/s, |dv_L| err %.4f m/s, peak tension "
      "%.1f N, min length after %.4f m, max closing speed after %.4f m/s\n",
      name, r.jump_mps, (r.v_Q_post - r.v_Q_predicted).norm(),
      (r.v_L_post - r.v_L_predicted).norm(), r.peak_tension_N, r.min_length_after_m,
      r.max_separating_vel_mps);
}

// Bounds from the measured values with solreflimit (0.002, 10) (models/scene.xml):
//   velocity error / jump: measured 0.1 % (vertical), 0.8 % (oblique; the rest is the centripetal
//   pull during the 5 ms window) -> bound 5 % (6x the worst);
//   closing speed after the snap: measured <= 4.1 mm/s -> bound 40 mm/s (10x);
//   cable length after the snap: measured >= l (never slack again) -> bound l - 1 mm, the truth
//   mode's taut threshold (a rebound would flip the true mode to slack).
void ExpectInelasticWithoutRebound(const RetautResult& r) {
  const double l = LoadParams(DefaultParamsPath()).cable_length_m;
  EXPECT_GT(r.jump_mps, 1.0) << "the case must actually snap";
  EXPECT_LT((r.v_Q_post - r.v_Q_predicted).norm(), 0.05 * r.jump_mps);
  EXPECT_LT((r.v_L_post - r.v_L_predicted).norm(), 0.05 * r.jump_mps);
  EXPECT_LT(r.max_separating_vel_mps, 0.04);
  EXPECT_GE(r.min_length_after_m, l - World::kTautLengthTolerance_m);
}

StateVector DropState(const Eigen::Vector3d& p_QL_W, const Eigen::Vector3d& v_L_W) {
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0, 0, 3.0);
  s.p_WL_W = s.p_WQ_W + p_QL_W;
  s.v_WL_W = v_L_W;
  return s.ToVector();
}

TEST(CableTest, VerticalSnapIsAnInelasticCollision) {
  // payload 0.35 m below the quadrotor falling at 2 m/s: snaps taut at about 2.6 m/s
  const RetautResult r =
      RunRetaut(DropState({0, 0, -0.35}, {0, 0, -2.0}), /*window_s=*/0.005, /*watch_s=*/0.3);
  Print("vertical", r);
  ExpectInelasticWithoutRebound(r);
}

TEST(CableTest, ObliqueSnapIsAnInelasticCollision) {
  // payload thrown sideways and down from 0.3 m off the quadrotor
  const RetautResult r = RunRetaut(DropState({0.2, 0.0, -0.2}, {1.0, 0.5, -1.5}), 0.005, 0.3);
  Print("oblique", r);
  ExpectInelasticWithoutRebound(r);
}

}  // namespace
}  // namespace hpa::sim
