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
  // settled: payload within 2 cm of its set point after 5 s (measured in the report)
  const Eigen::Vector3d rmse = testing_util::PayloadRmse(log, *ref, 4.0);
  std::printf("hover from offset: payload RMSE over [4, 5] s = %.4f %.4f %.4f m\n", rmse.x(),
              rmse.y(), rmse.z());
  EXPECT_LT(rmse.maxCoeff(), 0.02);
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
  // measured 0.67 m in z after 5 s (vs 0.0000 m with stage-0 thrust); bound at half of it
  EXPECT_GT(testing_util::PayloadRmse(log, *ref, 4.0).z(), 0.3);
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
      "slack throw: hpa_mpc min z %.3f m, max dev %.3f m; nonhybrid min z %.3f m, "
      "max dev %.3f m (finite %d)\n",
      min_z_hybrid, dev_hybrid, min_z_nonhybrid, dev_nonhybrid, nonhybrid_finite);
  // hybrid: never drops more than 15 cm below its set point (measured 0.008 m; 0.125 m before
  // the RTI line search) and stays within 40 cm of it (measured 0.295 m: the slack perception
  // cost, Q_cam 700, follows the horizontally thrown payload in x-y by design; 0.16 m at the
  // old Q_cam 20, which did not keep a payload moved by hand in view)
  EXPECT_GT(min_z_hybrid, p_q_ref.z() - 0.15);
  EXPECT_LT(dev_hybrid, 0.4);
  // The always-taut baseline is only printed: with the true payload state its outcome is
  // chaotic (it fell to the ground in one build and held 1.42 m after a rounding-level change
  // to the condensing); the paper's crash needs the always-taut estimator, which the lead's
  // MuJoCo scenario tests exercise.
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
      "lissajous T=5 s: payload RMSE after the ramp = %.4f %.4f %.4f m, "
      "max solve %.3f ms\n",
      rmse.x(), rmse.y(), rmse.z(), log.max_solve_ms);
  // paper, Table: 0.052 / 0.021 / 0.039 m on hardware at T = 5 s; on the analytic plant we
  // must do at least as well as the hardware figure x 1.5
  EXPECT_LT(rmse.x(), 1.5 * 0.052);
  EXPECT_LT(rmse.y(), 1.5 * 0.021 + 0.02);
  EXPECT_LT(rmse.z(), 1.5 * 0.039);
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
  std::printf("closed-loop cost over 1.5 s: RTI %.4f, NLopt %.4f, ratio %.3f\n", rti, nlopt,
              rti / nlopt);
  EXPECT_LT(rti, 1.15 * nlopt);
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
  const std::vector<Eigen::Vector3d> impulses_Ns = {
      {0.0, 0.0, 0.35}, {0.1, 0.05, 0.35}, {0.15, 0.1, 0.6}, {0.2, 0.0, 0.5}};
  for (const bool hybrid : {true, false}) {
    for (const Eigen::Vector3d& impulse_Ns : impulses_Ns) {
      auto mpc = MakeMpc(params, ref, hybrid);
      HybridPlant plant(params, HybridModel(params).HoverState(ref->At(0).p_WQ_W),
                        CableMode::kTaut);
      bool kicked = false;
      // the reference starts at t = 0 here (1 s in the scenario): kick at 2.5 s
      const auto kick = [&](double t, HybridPlant* p) {
        if (kicked || t < 2.5) return;
        kicked = true;
        StateVector x = p->x();
        x.segment<3>(StateIndex::kPayloadVel) += impulse_Ns / params.payload_mass_kg;
        *p = HybridPlant(params, x, CableMode::kSlack);
      };
      const auto log = RunClosedLoop(params, mpc.get(), &plant, 6.0, kick);
      ASSERT_TRUE(log.finite);
      double max_tilt_deg = 0.0, max_cmd_rate = 0.0, max_dev_m = 0.0;
      int failures = 0;
      for (size_t i = 0; i < log.states.size(); ++i) {
        const Eigen::Vector3d z_B = log.states[i].q_WB * Eigen::Vector3d::UnitZ();
        max_tilt_deg =
            std::max(max_tilt_deg, std::acos(std::clamp(z_B.z(), -1.0, 1.0)) * 180 / M_PI);
        max_cmd_rate =
            std::max(max_cmd_rate, log.outputs[i].command.w_B_radps.cwiseAbs().maxCoeff());
        max_dev_m = std::max(max_dev_m, (log.states[i].p_WQ_W - ref->At(log.t_s[i]).p_WQ_W).norm());
        const ControlStatus st = log.outputs[i].status;
        if (st != ControlStatus::kSuccess && st != ControlStatus::kMaxIterations) ++failures;
      }
      std::printf(
          "re-taut %s impulse [%.2f %.2f %.2f]: max tilt %.1f deg, max cmd rate %.1f rad/s, "
          "max quad dev %.3f m, failed solves %d\n",
          hybrid ? "hpa_mpc" : "nonhybrid_mpc", impulse_Ns.x(), impulse_Ns.y(), impulse_Ns.z(),
          max_tilt_deg, max_cmd_rate, max_dev_m, failures);
      EXPECT_LT(max_tilt_deg, 60.0);
    }
  }
}

}  // namespace
}  // namespace hpa
