// Closed-loop tests with hpa::HybridModel as the plant (ground-truth state and mode).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "closed_loop_sim.h"
#include "hpa/controller/hpa_mpc.h"

namespace hpa {
namespace {

using testing_util::HybridPlant;
using testing_util::RunClosedLoop;

std::unique_ptr<HpaMpc> MakeMpc(const Params& params, std::shared_ptr<Reference> ref, bool hybrid,
                                const std::string& solver = "rti") {
  MpcSettings settings;
  settings.hybrid = hybrid;
  settings.solver = solver;
  return std::make_unique<HpaMpc>(params, std::move(ref), settings);
}

TEST(ClosedLoopTest, HpaMpcHoverHoldsFromOffset) {
  const Params params;
  const auto ref = MakeHoverReference(params, Eigen::Vector3d(0, 0, 1.0));
  auto mpc = MakeMpc(params, ref, true);
  HybridPlant plant(params, HybridModel(params).HoverState(Eigen::Vector3d(0.3, -0.2, 1.3)),
                    CableMode::kTaut);
  const auto log = RunClosedLoop(params, mpc.get(), &plant, 5.0);
  ASSERT_TRUE(log.finite);
  for (const ControlOutput& out : log.outputs) EXPECT_EQ(out.status, ControlStatus::kSuccess);
  const Eigen::Vector3d rmse = testing_util::PayloadRmse(log, *ref, 4.0);
  // settling time: from then on the payload stays within 2 cm of its set point
  double settle_s = 0.0;
  for (size_t i = 0; i < log.states.size(); ++i) {
    const double error_m = (log.states[i].p_WL_W - ref->At(log.t_s[i]).p_WL_W).norm();
    if (error_m >= 0.02) settle_s = log.t_s[i];
  }
  std::printf(
      "hover from offset: payload RMSE over [4, 5] s = %.3e %.3e %.3e m (norm %.3e), "
      "settled within 2 cm at %.3f s\n",
      rmse.x(), rmse.y(), rmse.z(), rmse.norm(), settle_s);
  // measured: RMSE norm 4.546e-4 m, settling 1.114 s; bounds = measured x 1.4
  EXPECT_LT(rmse.norm(), 1.4 * 4.546e-4);
  EXPECT_LT(settle_s, 1.4 * 1.114);
  EXPECT_EQ(plant.mode(), CableMode::kTaut);
}

// Why the thrust comes from plan stage 0 (MpcSettings::thrust_output_stage): flying the
// stage-1 input never applies the plan's first input and leaves a standing altitude error.
TEST(ClosedLoopTest, StageOneThrustLeavesStandingError) {
  const Params params;
  const auto ref = MakeHoverReference(params, Eigen::Vector3d(0, 0, 1.0));
  MpcSettings settings;
  settings.thrust_output_stage = 1;
  HpaMpc mpc(params, ref, settings);
  HybridPlant plant(params, HybridModel(params).HoverState(Eigen::Vector3d(0.3, -0.2, 1.3)),
                    CableMode::kTaut);
  const auto log = RunClosedLoop(params, &mpc, &plant, 5.0);
  ASSERT_TRUE(log.finite);
  const double rmse_z = testing_util::PayloadRmse(log, *ref, 4.0).z();
  std::printf("stage-1 thrust: payload z RMSE over [4, 5] s = %.6f m\n", rmse_z);
  // measured 0.6736 m in z over [4, 5] s (1.6e-6 m with stage-0 thrust); bound = measured / 1.4
  EXPECT_GT(rmse_z, 0.6736 / 1.4);
}

// The payload is thrown up (cable slack) while hovering. The hybrid controller knows the
// payload is in free fall and tracks the quadrotor set point; it must not dive after it.
TEST(ClosedLoopTest, SlackPayloadDoesNotMakeHpaMpcDive) {
  const Params params;
  const auto ref = MakeHoverReference(params, Eigen::Vector3d(0, 0, 1.0));
  const Eigen::Vector3d p_q_ref = ref->At(0).p_WQ_W;
  auto run = [&](bool hybrid, double* min_z, double* max_dev) {
    auto mpc = MakeMpc(params, ref, hybrid);
    StateVector x0 = HybridModel(params).HoverState(p_q_ref);
    x0.segment<3>(StateIndex::kPayloadVel) = Eigen::Vector3d(0.5, 0.0, 3.0);  // thrown up
    HybridPlant plant(params, x0, CableMode::kSlack);
    const auto log = RunClosedLoop(params, mpc.get(), &plant, 3.0);
    *min_z = 1e9;
    *max_dev = 0.0;
    for (const SystemState& s : log.states) {
      *min_z = std::min(*min_z, s.p_WQ_W.z());
      *max_dev = std::max(*max_dev, (s.p_WQ_W - p_q_ref).norm());
    }
    return log.finite;
  };
  double min_z_hybrid, dev_hybrid, min_z_nonhybrid, dev_nonhybrid;
  ASSERT_TRUE(run(true, &min_z_hybrid, &dev_hybrid));
  const bool nonhybrid_finite = run(false, &min_z_nonhybrid, &dev_nonhybrid);
  std::printf(
      "slack throw: hpa_mpc drop %.5f m, max dev %.5f m; nonhybrid drop %.5f m, "
      "max dev %.5f m (finite %d)\n",
      p_q_ref.z() - min_z_hybrid, dev_hybrid, p_q_ref.z() - min_z_nonhybrid, dev_nonhybrid,
      nonhybrid_finite);
  // Measured drop below the set point / largest deviation from it: hpa_mpc 0.1206 / 0.1516 m,
  // nonhybrid_mpc 0.0689 / 0.1589 m. Both vary by < 0.1% when the throw speed changes by up to
  // 1e-3 relative (not chaotic here), so the bounds are measured x 1.4. With the true payload
  // state the baseline does not dive on this plant either; the paper's crash needs the
  // always-taut estimator, which the MuJoCo scenarios exercise.
  EXPECT_LT(p_q_ref.z() - min_z_hybrid, 1.4 * 0.1206);
  EXPECT_LT(dev_hybrid, 1.4 * 0.1516);
  ASSERT_TRUE(nonhybrid_finite);
  EXPECT_LT(p_q_ref.z() - min_z_nonhybrid, 1.4 * 0.0689);
  EXPECT_LT(dev_nonhybrid, 1.4 * 0.1589);
}

TEST(ClosedLoopTest, LissajousTracked) {
  const Params params;
  LissajousSpec spec;  // a = 2, b = 0.5, n = 2, flat z (c = 0), T = 5 s
  spec.psi = 1.0;
  const auto ref = MakeLissajousReference(params, spec);
  auto mpc = MakeMpc(params, ref, true);
  HybridPlant plant(params, HybridModel(params).HoverState(ref->At(0).p_WQ_W), CableMode::kTaut);
  const double duration_s = spec.ramp_s + 2 * spec.period_s;
  const auto log = RunClosedLoop(params, mpc.get(), &plant, duration_s);
  ASSERT_TRUE(log.finite);
  const Eigen::Vector3d rmse = testing_util::PayloadRmse(log, *ref, spec.ramp_s);
  std::printf(
      "lissajous T=5 s: payload RMSE after the ramp = %.6f %.6f %.6f m, "
      "max solve %.3f ms\n",
      rmse.x(), rmse.y(), rmse.z(), log.max_solve_ms);
  // measured 0.002764 / 0.005592 / 0.002254 m (the paper's hardware: 0.052 / 0.021 / 0.039 m
  // at T = 5 s); bounds = measured x 1.4
  EXPECT_LT(rmse.x(), 1.4 * 0.002764);
  EXPECT_LT(rmse.y(), 1.4 * 0.005592);
  EXPECT_LT(rmse.z(), 1.4 * 0.002254);
  EXPECT_EQ(plant.mode(), CableMode::kTaut);
}

// RTI (one SQP iteration per call) against the fully converged NLopt solve on the same short
// run: the closed-loop cost (sum of the OCP stage cost of the true trajectory) of RTI must be
// within a factor of NLopt's.
TEST(ClosedLoopTest, RtiCostCloseToNlopt) {
  const Params params;
  const auto ref = MakeHoverReference(params, Eigen::Vector3d(0, 0, 1.0));
  auto closed_loop_cost = [&](const std::string& solver) {
    auto mpc = MakeMpc(params, ref, true, solver);
    HybridPlant plant(params, HybridModel(params).HoverState(Eigen::Vector3d(0.3, -0.2, 1.3)),
                      CableMode::kTaut);
    const auto log = RunClosedLoop(params, mpc.get(), &plant, 1.5);
    EXPECT_TRUE(log.finite);
    double cost = 0.0;
    for (size_t i = 0; i < log.states.size(); ++i) {
      const Ocp ocp = mpc->BuildProblem(log.states[i]);
      ResidualVector r;
      // state part of the stage-0 cost of the true state (the input is the rate loop's)
      StageResidual(ocp, 0, log.states[i].ToVector(), ocp.u_ref[0], &r, nullptr, nullptr);
      cost += r.squaredNorm() / mpc->RateHz();
    }
    return cost;
  };
  const double rti = closed_loop_cost("rti");
  const double nlopt = closed_loop_cost("nlopt");
  std::printf("closed-loop cost over 1.5 s: RTI %.6f, NLopt %.6f, ratio %.5f\n", rti, nlopt,
              rti / nlopt);
  // measured RTI 22.646, NLopt 22.538 (ratio 1.005); bounds: ratio 1.15, each cost x 1.4
  EXPECT_LT(rti, 1.15 * nlopt);
  EXPECT_LT(rti, 1.4 * 22.646);
  EXPECT_LT(nlopt, 1.4 * 22.538);
}

// The paper's line with an impulse on the payload (scenarios/line_impulse.yaml with a sideways
// kick): the payload flies up beside the quadrotor and the cable snaps taut nearly horizontal
// with the payload falling fast. The full Gauss-Newton step of the plain RTI diverged there
// (plan cost 1e2 -> 1e23, commanded rates 20-40 rad/s, tilt past 90 deg); with the line search
// and Levenberg-Marquardt safeguard of RtiIteration both MPCs must ride it out.
TEST(ClosedLoopTest, RetautFromNearHorizontalCableDoesNotDiverge) {
  const Params params;
  const auto ref =
      MakeLineReference(params, Eigen::Vector3d(-1.5, 0, 0.8), Eigen::Vector3d(1.5, 0, 0.8), 6.0);
  // What each run measured (max tilt, max commanded body rate, max quadrotor deviation from its
  // reference, failed solves); the bounds are measured x 1.4.
  // hpa_mpc varies smoothly with the impulse (< 5% for a 1e-3 relative change): per impulse.
  // nonhybrid_mpc is chaotic here (a 1e-9 relative change of the impulse moves its deviation
  // from 0.47 to 0.81 m): one envelope over the four impulses each scaled by 1 +- {0, 1e-9,
  // 1e-6, 1e-3}, measured 43.7 deg, 14.9 rad/s, 0.875 m, 5 failed solves.
  struct Run {
    bool hybrid;
    Eigen::Vector3d impulse_Ns;
    double tilt_deg, rate_radps, dev_m;
    int failures;
  };
  const std::vector<Run> runs = {
      {true, {0.0, 0.0, 0.35}, 3.90, 0.40, 0.0336, 0},
      {true, {0.1, 0.05, 0.35}, 14.46, 3.44, 0.3173, 0},
      {true, {0.15, 0.1, 0.6}, 19.31, 5.31, 0.1642, 0},
      {true, {0.2, 0.0, 0.5}, 22.65, 7.92, 0.1801, 0},
      {false, {0.0, 0.0, 0.35}, 43.7, 14.9, 0.875, 5},
      {false, {0.1, 0.05, 0.35}, 43.7, 14.9, 0.875, 5},
      {false, {0.15, 0.1, 0.6}, 43.7, 14.9, 0.875, 5},
      {false, {0.2, 0.0, 0.5}, 43.7, 14.9, 0.875, 5},
  };
  for (const Run& run : runs) {
    auto mpc = MakeMpc(params, ref, run.hybrid);
    HybridPlant plant(params, HybridModel(params).HoverState(ref->At(0).p_WQ_W), CableMode::kTaut);
    bool kicked = false;
    // the reference starts at t = 0 here (1 s in the scenario): kick at 2.5 s
    const auto kick = [&](double t, HybridPlant* p) {
      if (kicked || t < 2.5) return;
      kicked = true;
      StateVector x = p->x();
      x.segment<3>(StateIndex::kPayloadVel) += run.impulse_Ns / params.payload_mass_kg;
      *p = HybridPlant(params, x, CableMode::kSlack);
    };
    const auto log = RunClosedLoop(params, mpc.get(), &plant, 6.0, kick);
    ASSERT_TRUE(log.finite);
    double max_tilt_deg = 0.0, max_cmd_rate = 0.0, max_dev_m = 0.0;
    int failures = 0;
    for (size_t i = 0; i < log.states.size(); ++i) {
      const Eigen::Vector3d z_B = log.states[i].q_WB * Eigen::Vector3d::UnitZ();
      max_tilt_deg = std::max(max_tilt_deg, std::acos(std::clamp(z_B.z(), -1.0, 1.0)) * 180 / M_PI);
      max_cmd_rate = std::max(max_cmd_rate, log.outputs[i].command.w_B_radps.cwiseAbs().maxCoeff());
      max_dev_m = std::max(max_dev_m, (log.states[i].p_WQ_W - ref->At(log.t_s[i]).p_WQ_W).norm());
      const ControlStatus st = log.outputs[i].status;
      if (st != ControlStatus::kSuccess && st != ControlStatus::kMaxIterations) ++failures;
    }
    const char* name = run.hybrid ? "hpa_mpc" : "nonhybrid_mpc";
    std::printf(
        "re-taut %s impulse [%.2f %.2f %.2f]: max tilt %.2f deg, max cmd rate %.2f rad/s, "
        "max quad dev %.4f m, failed solves %d\n",
        name, run.impulse_Ns.x(), run.impulse_Ns.y(), run.impulse_Ns.z(), max_tilt_deg,
        max_cmd_rate, max_dev_m, failures);
    EXPECT_LT(max_tilt_deg, 1.4 * run.tilt_deg) << name;
    EXPECT_LT(max_cmd_rate, 1.4 * run.rate_radps) << name;
    EXPECT_LT(max_dev_m, 1.4 * run.dev_m) << name;
    EXPECT_LE(failures, static_cast<int>(1.4 * run.failures)) << name;
  }
}

}  // namespace
}  // namespace hpa
