// The OCP solver registry: the built-ins behind the interface, a toy solver registered at run
// time and flown by HpaMpc, refusals.

#include "hpa/controller/ocp_solver.h"

#include <gtest/gtest.h>

#include <stdexcept>

#include "hpa/controller/controller_registry.h"
#include "hpa/controller/hpa_mpc.h"

namespace hpa {
namespace {

// Returns the guess clamped into the bounds: the smallest solver there is.
class HoldGuessSolver : public OcpSolver {
 public:
  OcpSolution Solve(const Ocp& ocp, const StateVector& x0,
                    const std::vector<InputVector>& u_guess) override {
    OcpSolution solution;
    for (const InputVector& u : u_guess) {
      solution.u.push_back(u.cwiseMax(ocp.u_min_radps).cwiseMin(ocp.u_max_radps));
    }
    solution.cost = OcpCost(ocp, x0, solution.u, &solution.x);
    return solution;
  }
  std::unique_ptr<OcpSolver> Clone() const override {
    return std::make_unique<HoldGuessSolver>(*this);
  }
};

std::shared_ptr<Reference> HoverRef(const Params& params) {
  return MakeHoverReference(params, Eigen::Vector3d(0, 0, 1.0));
}

TEST(OcpSolverTest, ListsTheBuiltIns) {
  const std::vector<std::string> names = OcpSolverNames();
  ASSERT_GE(names.size(), 2u);
  EXPECT_EQ(names[0], "rti");
  EXPECT_EQ(names[1], "nlopt");
  ASSERT_EQ(names.size(), OcpSolvers().size());
  for (const OcpSolverRegistration& r : OcpSolvers()) {
    EXPECT_FALSE(r.description.empty()) << r.name;
    EXPECT_EQ(FindOcpSolver(r.name), &r);
    EXPECT_NE(MakeOcpSolver(r.name, OcpSolverSettings()), nullptr) << r.name;
  }
  EXPECT_EQ(FindOcpSolver("ipopt"), nullptr);
  try {
    MakeOcpSolver("ipopt", OcpSolverSettings());
    FAIL() << "ipopt accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("nlopt"), std::string::npos) << e.what();
  }
}

// Behind the interface each built-in gives exactly what its own entry point gives.
TEST(OcpSolverTest, BuiltInsAreTheirEntryPoints) {
  const Params params;
  const Ocp ocp = BuildOcp(params, *HoverRef(params), 0.0, CableMode::kTaut, 1.0);
  const StateVector x0 = ocp.model->HoverState(Eigen::Vector3d(0.3, -0.2, 1.4));
  const std::vector<InputVector> guess(ocp.horizon_steps, ocp.u_ref[0]);
  OcpSolverSettings settings;
  settings.nlopt.max_evaluations = 50;
  const OcpSolution rti = MakeOcpSolver("rti", settings)->Solve(ocp, x0, guess);
  const RtiResult rti_direct = RtiIteration(ocp, x0, guess, settings.rti);
  EXPECT_EQ(rti.status, rti_direct.status);
  EXPECT_EQ(rti.cost, rti_direct.cost);
  EXPECT_EQ(rti.u, rti_direct.u);
  EXPECT_EQ(rti.x, rti_direct.x);
  const OcpSolution nlopt = MakeOcpSolver("nlopt", settings)->Solve(ocp, x0, guess);
  const NloptResult nlopt_direct = NloptSolve(ocp, x0, guess, settings.nlopt);
  EXPECT_EQ(nlopt.status, nlopt_direct.status);
  EXPECT_EQ(nlopt.cost, nlopt_direct.cost);
  EXPECT_EQ(nlopt.u, nlopt_direct.u);
  // the settings reach the solver: 50 evaluations do not converge from this offset
  EXPECT_EQ(nlopt.status, ControlStatus::kMaxIterations);
}

TEST(OcpSolverTest, AToySolverIsOneRegistration) {
  if (FindOcpSolver("hold_guess") == nullptr) {
    RegisterOcpSolver({"hold_guess", "returns the warm start", [](const OcpSolverSettings&) {
                         return std::make_unique<HoldGuessSolver>();
                       }});
  }
  EXPECT_EQ(OcpSolverNames().back(), "hold_guess");
  const Params params;
  // the scenario-level factory accepts it, and the MPC flies it: the plan is the warm start
  ControllerConfig config;
  config.settings["solver"] = std::string("hold_guess");
  std::unique_ptr<Controller> controller = MakeController(config, params, HoverRef(params));
  auto* mpc = dynamic_cast<HpaMpc*>(controller.get());
  ASSERT_NE(mpc, nullptr);
  SystemState s;
  s.FromVector(mpc->model().HoverState(Eigen::Vector3d(0.2, 0, 1.5)));
  const std::vector<InputVector> guess = mpc->WarmStart(0.0);
  const ControlOutput out = mpc->Update(s);
  EXPECT_EQ(out.status, ControlStatus::kSuccess);
  EXPECT_EQ(mpc->plan_inputs(), guess);
  // (the hybrid MPC starts a taut prediction from the state projected onto the cable)
  const StateVector x0 = mpc->model().ProjectToTaut(s.ToVector());
  EXPECT_EQ(out.cost, OcpCost(mpc->BuildProblem(s), x0, guess));
}

TEST(OcpSolverTest, DuplicatesEmptyNamesAndMissingFactoriesAreRefused) {
  const OcpSolverFactory make = [](const OcpSolverSettings&) {
    return std::make_unique<HoldGuessSolver>();
  };
  EXPECT_THROW(RegisterOcpSolver({"rti", "again", make}), std::invalid_argument);
  EXPECT_THROW(RegisterOcpSolver({"", "nameless", make}), std::invalid_argument);
  EXPECT_THROW(RegisterOcpSolver({"no_factory", "x", nullptr}), std::invalid_argument);
}

// A copied HpaMpc has its own solver (a clone) and continues exactly like the original.
TEST(OcpSolverTest, CopiedMpcClonesItsSolver) {
  const Params params;
  HpaMpc mpc(params, HoverRef(params), MpcSettings());
  SystemState s;
  s.FromVector(mpc.model().HoverState(Eigen::Vector3d(0.2, -0.1, 1.4)));
  mpc.Update(s);
  HpaMpc copy = mpc;
  s.time_s = 1.0 / 150.0;
  const ControlOutput a = mpc.Update(s);
  const ControlOutput b = copy.Update(s);
  EXPECT_EQ(a.cost, b.cost);
  EXPECT_EQ(mpc.plan_inputs(), copy.plan_inputs());
}

}  // namespace
}  // namespace hpa
