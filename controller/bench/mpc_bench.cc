// mpc_bench: cost of one HPA-MPC update (RTI and NLopt) from a realistic warm-started state,
// and of its parts. Run with --benchmark_repetitions=20 --benchmark_report_aggregates_only=true
// for the median; BM_HpaMpcRtiStepDistribution reports p50/p99 of single calls.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <ctime>

#include "../tests/closed_loop_sim.h"
#include "box_qp.h"
#include "condensing.h"
#include "exact_derivatives.h"
#include "hpa/controller/hpa_mpc.h"
#include "riccati_qp.h"

namespace hpa {
namespace {

// The RTI's default QP method.
RtiQpMethod RtiQpSettingsDefault() { return RtiSettings().qp_method; }

// A controller and state 3 s into the paper's Lissajous (a = 2, b = 0.5, n = 2, T = 5 s),
// reached by flying the closed loop on the analytic plant, so the plan is warm.
struct WarmScenario {
  Params params;
  std::shared_ptr<Reference> ref;
  std::unique_ptr<HpaMpc> mpc;
  SystemState state;

  explicit WarmScenario(const std::string& solver, RtiQpMethod qp_method = RtiQpSettingsDefault()) {
    ref = MakeLissajousReference(params, LissajousSpec());
    MpcSettings settings;
    settings.solver = solver;
    settings.solvers.rti.qp_method = qp_method;
    mpc = std::make_unique<HpaMpc>(params, ref, settings);
    MpcSettings flown;  // RTI with this scenario's QP method
    flown.solvers.rti.qp_method = qp_method;
    HpaMpc rti(params, ref, flown);
    testing_util::HybridPlant plant(params, HybridModel(params).HoverState(ref->At(0).p_WQ_W),
                                    CableMode::kTaut);
    testing_util::RunClosedLoop(params, &rti, &plant, 3.0);
    state = plant.State(3.0);
    // give the benchmarked controller the plan of the flown one
    *mpc = rti;
    if (solver == "nlopt") {
      MpcSettings s = settings;
      *mpc = HpaMpc(params, ref, s);
      mpc->Update(state);
    }
    state.time_s += 1.0 / 150.0;
  }
};

void BM_HpaMpcRtiStep(benchmark::State& st) {
  WarmScenario sc("rti");
  const HpaMpc saved = *sc.mpc;
  for (auto _ : st) {
    st.PauseTiming();
    *sc.mpc = saved;
    st.ResumeTiming();
    benchmark::DoNotOptimize(sc.mpc->Update(sc.state));
  }
}
BENCHMARK(BM_HpaMpcRtiStep)->Unit(benchmark::kMicrosecond);

// BM_HpaMpcRtiStep with each QP method: 0 dense condensing, 1 structured condensing, 2 Riccati.
void BM_HpaMpcRtiStepQpMethod(benchmark::State& st) {
  WarmScenario sc("rti", static_cast<RtiQpMethod>(st.range(0)));
  const HpaMpc saved = *sc.mpc;
  for (auto _ : st) {
    st.PauseTiming();
    *sc.mpc = saved;
    st.ResumeTiming();
    benchmark::DoNotOptimize(sc.mpc->Update(sc.state));
  }
}
BENCHMARK(BM_HpaMpcRtiStepQpMethod)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

// Thread CPU time in ms (excludes preemption by other processes on a shared machine).
double ThreadCpuMs() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

// Single-call distribution over 300 consecutive control steps (2 s) from the warm state of a
// flown Lissajous, with the plan evolving: p50, p99 and max of the wall time (what
// ControlOutput::solve_time_ms reports) and of the thread CPU time.
void BM_HpaMpcRtiStepDistribution(benchmark::State& st) {
  WarmScenario sc("rti");
  std::vector<double> wall_ms, cpu_ms;
  for (auto _ : st) {
    wall_ms.clear();
    cpu_ms.clear();
    HpaMpc mpc = *sc.mpc;
    SystemState s = sc.state;
    for (int i = 0; i < 300; ++i) {
      s.time_s += 1.0 / 150.0;
      const double cpu0 = ThreadCpuMs();
      wall_ms.push_back(mpc.Update(s).solve_time_ms);
      cpu_ms.push_back(ThreadCpuMs() - cpu0);
    }
  }
  for (auto* v : {&wall_ms, &cpu_ms}) std::sort(v->begin(), v->end());
  st.counters["p50_ms"] = wall_ms[wall_ms.size() / 2];
  st.counters["p99_ms"] = wall_ms[wall_ms.size() * 99 / 100];
  st.counters["max_ms"] = wall_ms.back();
  st.counters["cpu_p50_ms"] = cpu_ms[cpu_ms.size() / 2];
  st.counters["cpu_p99_ms"] = cpu_ms[cpu_ms.size() * 99 / 100];
}
BENCHMARK(BM_HpaMpcRtiStepDistribution)->Unit(benchmark::kMillisecond)->Iterations(3);

// One RTI call in slack mode, the payload thrown up 0.2 m above its hanging place at 0.5 m/s (it
// meets the cable again 0.26 s into the horizon), from the warm Lissajous plan: the paper's
// slack horizon (arg 0) against the re-taut predicted inside it (arg 1, controller.predict_retaut).
void BM_HpaMpcRtiStepSlack(benchmark::State& st) {
  WarmScenario sc("rti");
  MpcSettings settings;
  settings.predict_retaut = st.range(0) != 0;
  HpaMpc mpc(sc.params, sc.ref, settings);
  SystemState s = sc.state;
  s.mode = CableMode::kSlack;
  s.p_WL_W = s.p_WQ_W + Eigen::Vector3d(0.02, 0.0, -0.3);
  s.v_WL_W = s.v_WQ_W + Eigen::Vector3d(0.0, 0.0, 0.5);
  int scheduled = 0;
  for (auto _ : st) {
    st.PauseTiming();
    mpc = HpaMpc(sc.params, sc.ref, settings);
    static_cast<void>(mpc.Update(sc.state));  // warm plan, then the slack call is timed
    scheduled = mpc.BuildProblem(s).retaut_stage;
    st.ResumeTiming();
    benchmark::DoNotOptimize(mpc.Update(s));
  }
  st.counters["retaut_stage"] = scheduled;
}
BENCHMARK(BM_HpaMpcRtiStepSlack)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

void BM_HpaMpcNloptSolve(benchmark::State& st) {
  WarmScenario sc("nlopt");
  const HpaMpc saved = *sc.mpc;
  for (auto _ : st) {
    st.PauseTiming();
    *sc.mpc = saved;
    st.ResumeTiming();
    benchmark::DoNotOptimize(sc.mpc->Update(sc.state));
  }
}
BENCHMARK(BM_HpaMpcNloptSolve)->Unit(benchmark::kMillisecond);

// Parts of one RTI call. The RK4 step's Jacobians: hand-derived (what the OCP uses) and by
// forward-mode AD (HybridModel::StepJacobians, the reference the tests compare with).
// Times step_jacobians(model, x, u, &x_next, &a, &b) at a warm scenario's state and planned input.
template <typename StepJacobians>
void TimeStepJacobians(benchmark::State& st, const StepJacobians& step_jacobians) {
  WarmScenario sc("rti");
  const InputVector u = sc.mpc->plan_inputs()[0];
  const StateVector x = sc.state.ToVector();
  StateVector x_next;
  StateMatrix a;
  InputMatrix b;
  for (auto _ : st) {
    step_jacobians(sc.mpc->model(), x, u, &x_next, &a, &b);
    benchmark::DoNotOptimize(a);
  }
}

void BM_StepJacobians(benchmark::State& st) {
  TimeStepJacobians(st, [](const HybridModel& model, const StateVector& x, const InputVector& u,
                           StateVector* x_next, StateMatrix* a, InputMatrix* b) {
    ExactStepJacobians(model, x, u, CableMode::kTaut, 0.1, x_next, a, b);
  });
}
BENCHMARK(BM_StepJacobians)->Unit(benchmark::kMicrosecond);

void BM_StepJacobiansAutoDiff(benchmark::State& st) {
  TimeStepJacobians(st, [](const HybridModel& model, const StateVector& x, const InputVector& u,
                           StateVector* x_next, StateMatrix* a, InputMatrix* b) {
    model.StepJacobians(x, u, CableMode::kTaut, 0.1, x_next, a, b);
  });
}
BENCHMARK(BM_StepJacobiansAutoDiff)->Unit(benchmark::kMicrosecond);

// The linearisation of one RTI (simulated states, step Jacobians, stage residuals and their
// Jacobians) along the warm start, into kept vectors.
void BM_LinearizeAlong(benchmark::State& st) {
  WarmScenario sc("rti");
  const Ocp ocp = sc.mpc->BuildProblem(sc.state);
  const std::vector<InputVector> u = sc.mpc->WarmStart(sc.state.time_s);
  OcpLinearization lin;
  for (auto _ : st) {
    LinearizeAlong(ocp, sc.state.ToVector(), u, &lin);
    benchmark::DoNotOptimize(lin.cost);
  }
}
BENCHMARK(BM_LinearizeAlong)->Unit(benchmark::kMicrosecond);

// The Gauss-Newton stage models of one RTI (N + 1 stages) from its linearisation.
void BM_GaussNewtonStages(benchmark::State& st) {
  WarmScenario sc("rti");
  const Ocp ocp = sc.mpc->BuildProblem(sc.state);
  const OcpLinearization lin =
      LinearizeAlong(ocp, sc.state.ToVector(), sc.mpc->WarmStart(sc.state.time_s));
  std::vector<StageQuadratic> stages(ocp.horizon_steps + 1);
  for (auto _ : st) {
    for (int k = 0; k <= ocp.horizon_steps; ++k) {
      GaussNewtonStage(lin.r[k], lin.r_x[k], lin.r_u[k], OcpResidualColumns(), &stages[k]);
    }
    benchmark::DoNotOptimize(stages.data());
  }
}
BENCHMARK(BM_GaussNewtonStages)->Unit(benchmark::kMicrosecond);

// The QP of one RTI: arg 0 Condense + dense box QP, arg 1 CondenseStructured + dense box QP,
// arg 2 the Riccati box QP (no condensing); workspaces kept.
void BM_CondenseAndQp(benchmark::State& st) {
  WarmScenario sc("rti");
  const Ocp ocp = sc.mpc->BuildProblem(sc.state);
  const int n = ocp.horizon_steps;
  const std::vector<InputVector> u = sc.mpc->WarmStart(sc.state.time_s);
  const OcpLinearization lin = LinearizeAlong(ocp, sc.state.ToVector(), u);
  std::vector<StageQuadratic> stages(n + 1);
  for (int k = 0; k <= n; ++k) stages[k] = GaussNewtonStage(lin.r[k], lin.r_x[k], lin.r_u[k]);
  Eigen::VectorXd lb(kNu * n), ub(kNu * n);
  for (int k = 0; k < n; ++k) {
    lb.segment<kNu>(kNu * k) = ocp.u_min_radps - u[k];
    ub.segment<kNu>(kNu * k) = ocp.u_max_radps - u[k];
  }
  Eigen::MatrixXd h;
  Eigen::VectorXd g;
  Eigen::VectorXd du(kNu * n);
  CondensingWorkspace condensing;
  BoxQpWorkspace qp;
  RiccatiWorkspace riccati;
  for (auto _ : st) {
    du.setZero();
    if (st.range(0) == 2) {
      benchmark::DoNotOptimize(SolveRiccatiBoxQp(lin.a, lin.b, stages, 0.0, lb, ub, &du, &riccati));
      continue;
    }
    if (st.range(0) == 0) {
      Condense(lin.a, lin.b, stages, &condensing, &h, &g);
    } else {
      CondenseStructured(lin.a, lin.b, stages, &condensing, &h, &g);
    }
    benchmark::DoNotOptimize(SolveBoxQp(h, g, lb, ub, &du, &qp));
  }
}
BENCHMARK(BM_CondenseAndQp)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace hpa

BENCHMARK_MAIN();
