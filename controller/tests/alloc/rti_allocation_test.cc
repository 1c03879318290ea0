// A steady-state RTI step allocates no heap memory: its own binary, with global operator new
// replaced by a counting one (the count is taken only around the step under test).

#include <gtest/gtest.h>

#include "hpa/controller/hpa_mpc.h"
#include "hpa/controller/rti_solver.h"
#include "models/tests/support/counting_allocator.h"

namespace hpa {
namespace {

using test_support::CountAllocations;

TEST(RtiAllocationTest, CountingAllocatorSeesAllocations) {
  EXPECT_GT(CountAllocations([]() { std::vector<int> v(10); }), 0);
}

// Lissajous tracking from an offset hover state, taut and slack (L_cam on), every QP method:
// after two warm-up iterations with the same workspace and result, an RTI step (linearisation,
// stage models, condensing, box QP, line search) allocates nothing.
TEST(RtiAllocationTest, SteadyStateStepAllocatesNothing) {
  const Params params;
  const auto ref = MakeLissajousReference(params, LissajousSpec());
  for (CableMode mode : {CableMode::kTaut, CableMode::kSlack}) {
    for (RtiQpMethod method : {RtiQpMethod::kStructuredCondensing, RtiQpMethod::kDenseCondensing,
                               RtiQpMethod::kRiccati}) {
      const Ocp ocp = BuildOcp(params, *ref, 0.7, mode, 1.0);
      StateVector x0 = HybridModel(params).HoverState(ref->At(0.7).p_WQ_W);
      x0(StateIndex::kQuadPos) += 0.2;
      RtiSettings settings;
      settings.qp_method = method;
      RtiWorkspace workspace;
      RtiResult result;
      std::vector<InputVector> guess(ocp.horizon_steps,
                                     InputVector::Constant(params.HoverMotorSpeedRadps()));
      for (int i = 0; i < 2; ++i) {
        RtiIteration(ocp, x0, guess, settings, &workspace, &result);
        guess = result.u;
      }
      const long allocations =
          CountAllocations([&]() { RtiIteration(ocp, x0, guess, settings, &workspace, &result); });
      EXPECT_EQ(allocations, 0) << ToString(mode) << " qp method " << static_cast<int>(method);
      EXPECT_EQ(result.status, ControlStatus::kSuccess);
      EXPECT_GT(result.step, 0.0);
    }
  }
}

// The whole controller update (warm start, problem building, RTI, plan swap) of hpa_mpc, taut and
// slack (re-taut prediction on), allocates nothing once it has run a few times.
TEST(RtiAllocationTest, SteadyStateMpcUpdateAllocatesNothing) {
  const Params params;
  const auto ref = MakeLissajousReference(params, LissajousSpec());
  for (CableMode mode : {CableMode::kTaut, CableMode::kSlack}) {
    MpcSettings settings;
    settings.predict_retaut = true;
    HpaMpc mpc(params, ref, settings);
    SystemState s;
    s.FromVector(HybridModel(params).HoverState(ref->At(0.0).p_WQ_W));
    s.mode = mode;
    for (int i = 0; i < 3; ++i) {
      s.time_s = i / settings.rate_hz;
      static_cast<void>(mpc.Update(s));
    }
    s.time_s = 3 / settings.rate_hz;
    ControlOutput out;
    EXPECT_EQ(CountAllocations([&]() { out = mpc.Update(s); }), 0) << ToString(mode);
    EXPECT_EQ(out.status, ControlStatus::kSuccess) << ToString(mode);
  }
}

}  // namespace
}  // namespace hpa
