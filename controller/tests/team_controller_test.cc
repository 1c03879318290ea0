#include "hpa/controller/team_controller.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "hpa/controller/cooperative_controller.h"
#include "hpa/controller/hpa_mpc.h"
#include "hpa/models/params.h"
#include "team_plant.h"

namespace hpa {
namespace {

using testing_util::PayloadMaxErrorM;
using testing_util::PayloadMaxTiltRad;
using testing_util::PayloadRmseM;
using testing_util::RunTeam;
using testing_util::TeamPlant;
using testing_util::TeamRunLog;

// The shipped vehicle: models/params.yaml through the loader.
Params DefaultParams() { return LoadParams(std::string(HPA_SOURCE_DIR) + "/models/params.yaml"); }

// Two vehicles on RotorTM's long bar (rotor_tm_config/config/load_params/long_bar_wood_payload.yaml
// and attach_mechanism/cable/2_robots_long_bar_payload_0-5m.yaml): 0.104 kg, cables of 0.5 m at
// the bar's ends, just above its centre of mass.
CooperativeTeam BarTeam() {
  CooperativeTeam team;
  team.payload_mass_kg = 0.104;
  team.payload_inertia_P_kgm2 = Eigen::Vector3d(0.004053, 0.000013225, 0.004053);
  for (const double y_m : {-0.19, 0.19}) {
    CooperativeVehicle v;
    v.params = DefaultParams();
    v.cable_length_m = 0.5;
    v.p_PA_P_m = Eigen::Vector3d(0.0, y_m, 0.0097);
    team.vehicles.push_back(v);
  }
  return team;
}

// Three vehicles on RotorTM's triangular payload (load_params/triangular_payload.yaml and
// attach_mechanism/cable/3_robots_triangular_payload_0-5m.yaml): 0.278 kg, cables of 0.5 m at the
// corners.
CooperativeTeam TriangleTeam() {
  CooperativeTeam team;
  team.payload_mass_kg = 0.278;
  team.payload_inertia_P_kgm2 = Eigen::Vector3d(0.00625019392, 0.00625019392, 0.01245978846);
  const Eigen::Vector3d corners[3] = {
      {-0.1540, -0.267, 0.01125}, {0.3083, 0.0, 0.01125}, {-0.1540, 0.267, 0.01125}};
  for (const Eigen::Vector3d& p_PA_P_m : corners) {
    CooperativeVehicle v;
    v.params = DefaultParams();
    v.cable_length_m = 0.5;
    v.p_PA_P_m = p_PA_P_m;
    team.vehicles.push_back(v);
  }
  return team;
}

// One vehicle with its payload at the cable's end (a point mass).
CooperativeTeam SingleTeam() { return CooperativeTeam::SingleVehicle(DefaultParams()); }

// Every vehicle's controller of `type` for the team.
std::vector<std::unique_ptr<TeamController>> MakeTeam(const std::string& type,
                                                      const CooperativeTeam& team,
                                                      std::shared_ptr<const Reference> reference) {
  std::vector<std::unique_ptr<TeamController>> controllers;
  for (int i = 0; i < static_cast<int>(team.vehicles.size()); ++i) {
    controllers.push_back(MakeTeamController(type, team, i, reference));
  }
  return controllers;
}

// Flies the team of `type` from the hanging layout at `start` along `reference`.
TeamRunLog Fly(const std::string& type, const CooperativeTeam& team,
               std::shared_ptr<const Reference> reference, const Eigen::Vector3d& start,
               double duration_s) {
  const auto controllers = MakeTeam(type, team, reference);
  std::vector<TeamController*> raw;
  for (const auto& c : controllers) raw.push_back(c.get());
  TeamPlant plant(team, CooperativeModel(team).HangingState(start));
  return RunTeam(&plant, raw, duration_s);
}

// Every update succeeded (an MPC may stop at its iteration limit: still a plan).
void ExpectUsableStatuses(const TeamRunLog& log) {
  for (ControlStatus s : log.statuses) {
    EXPECT_TRUE(s == ControlStatus::kSuccess || s == ControlStatus::kMaxIterations) << ToString(s);
  }
}

const Eigen::Vector3d kStart(0.0, 0.0, 1.0);     // payload's start and hover position, world (3)
const Eigen::Vector3d kEnd(2.0, 0.0, 1.0);       // the line's end, 2 m along x, world (3)
const Eigen::Vector3d kOffset(0.2, -0.2, -0.1);  // offset start's distance from kStart (3)
constexpr double kLineS = 4.0;                   // the line's duration
constexpr double kLineRunS = 6.0;                // the line plus 2 s to settle
constexpr double kHoverS = 5.0;                  // hover hold

// One flight case: a controller type on a named team, and the bounds its flights must meet.
struct Case {
  std::string type;
  std::string team_name;
  double hover_max_error_m;  // bound on the hover hold's largest payload error
  double offset_settled_m;   // bound on the largest error over the offset start's last second
  double line_rmse_m;        // bound on the line's payload RMSE
};

// The team of a case: "bar", "triangle" or "single".
CooperativeTeam TeamNamed(const std::string& name) {
  if (name == "bar") return BarTeam();
  if (name == "triangle") return TriangleTeam();
  return SingleTeam();
}

// The flights of one case.
class TeamFlightTest : public testing::TestWithParam<Case> {};

// (a), (c): hold the payload from the hanging layout at the reference.
TEST_P(TeamFlightTest, HoverHold) {
  const Case& c = GetParam();
  const CooperativeTeam team = TeamNamed(c.team_name);
  const auto reference = MakeHoverReference(team.vehicles[0].params, kStart);
  const TeamRunLog log = Fly(c.type, team, reference, kStart, kHoverS);
  ASSERT_TRUE(log.finite);
  ExpectUsableStatuses(log);
  const double max_error_m = PayloadMaxErrorM(log, *reference);
  std::printf("%s %s hover: max payload error %.4g m, max tilt %.4g rad, slack steps %d\n",
              c.type.c_str(), c.team_name.c_str(), max_error_m, PayloadMaxTiltRad(log),
              log.slack_plant_steps);
  EXPECT_LT(max_error_m, c.hover_max_error_m);
  EXPECT_EQ(log.slack_plant_steps, 0);
}

// (a), (c): from the hanging layout 0.3 m off the hover reference, settled within the 5 s hold.
TEST_P(TeamFlightTest, HoverFromOffset) {
  const Case& c = GetParam();
  const CooperativeTeam team = TeamNamed(c.team_name);
  const auto reference = MakeHoverReference(team.vehicles[0].params, kStart);
  const TeamRunLog log = Fly(c.type, team, reference, kStart + kOffset, kHoverS);
  ASSERT_TRUE(log.finite);
  ExpectUsableStatuses(log);
  double settled_m = 0.0;
  for (size_t k = 0; k < log.t_s.size(); ++k) {
    if (log.t_s[k] >= kHoverS - 1.0)
      settled_m = std::max(settled_m, (log.p_WL_W[k] - kStart).norm());
  }
  std::printf(
      "%s %s offset start: payload error over the last second %.4g m, RMSE %.4g m, "
      "max tilt %.4g rad, slack steps %d\n",
      c.type.c_str(), c.team_name.c_str(), settled_m, PayloadRmseM(log, *reference),
      PayloadMaxTiltRad(log), log.slack_plant_steps);
  EXPECT_LT(settled_m, c.offset_settled_m);
}

// (b), (c), (f): a 2 m line in 4 s.
TEST_P(TeamFlightTest, Line) {
  const Case& c = GetParam();
  const CooperativeTeam team = TeamNamed(c.team_name);
  const auto reference = MakeLineReference(team.vehicles[0].params, kStart, kEnd, kLineS);
  const TeamRunLog log = Fly(c.type, team, reference, kStart, kLineRunS);
  ASSERT_TRUE(log.finite);
  ExpectUsableStatuses(log);
  const double rmse_m = PayloadRmseM(log, *reference);
  std::printf(
      "%s %s line: payload RMSE %.4g m, max error %.4g m, final error %.4g m, "
      "max tilt %.4g rad, slack steps %d\n",
      c.type.c_str(), c.team_name.c_str(), rmse_m, PayloadMaxErrorM(log, *reference),
      (log.p_WL_W.back() - kEnd).norm(), PayloadMaxTiltRad(log), log.slack_plant_steps);
  EXPECT_LT(rmse_m, c.line_rmse_m);
}

// Bounds: the measured error with margin so a 50% regression fails. The cooperative hover
// starts at its controller's exact equilibrium (the hanging layout, cable forces straight up
// from pinv(P)), so its bound is rounding's; the MPC's hover bound is its measured drift (its
// perception term and the solver's tolerance) with that margin.
INSTANTIATE_TEST_SUITE_P(Teams, TeamFlightTest,
                         testing::Values(Case{"cooperative", "bar", 1e-12, 0.026, 0.09},
                                         Case{"cooperative", "triangle", 1e-12, 0.010, 0.092},
                                         Case{"cooperative", "single", 1e-12, 0.010, 0.092},
                                         Case{"hpa_mpc", "bar", 6.8e-5, 1.25e-3, 0.0093},
                                         Case{"hpa_mpc", "triangle", 1.7e-4, 1.0e-3, 0.0087},
                                         Case{"hpa_mpc", "single", 2.1e-4, 1.0e-3, 0.0086}),
                         [](const testing::TestParamInfo<Case>& info) {
                           return info.param.type + "_" + info.param.team_name;
                         });

// (d): a non-finite view gives kNonFinite and a finite, level-out command.
TEST(TeamControllerTest, NonFiniteViewGivesSafeCommand) {
  const CooperativeTeam team = TriangleTeam();
  const auto reference = MakeHoverReference(team.vehicles[0].params, kStart);
  for (const std::string& type : TeamControllerNames()) {
    for (int field = 0; field < 4; ++field) {
      auto controller = MakeTeamController(type, team, 1, reference);
      TeamPlant plant(team, CooperativeModel(team).HangingState(kStart));
      TeamView view = plant.View(1, 0.0);
      const double nan = std::numeric_limits<double>::quiet_NaN();
      if (field == 0) view.p_WL_W.x() = nan;
      if (field == 1) view.w_P.z() = std::numeric_limits<double>::infinity();
      if (field == 2) view.time_s = nan;
      if (field == 3) view.q_WB.w() = nan;
      const ControlOutput out = controller->Update(view);
      EXPECT_EQ(out.status, ControlStatus::kNonFinite) << type << " field " << field;
      EXPECT_TRUE(out.command.w_B_radps.allFinite()) << type;
      EXPECT_TRUE(std::isfinite(out.command.thrust_N)) << type;
      EXPECT_GT(out.command.thrust_N, 0.0) << type;
      // the vehicle is level (or its attitude unknown): the level-out commands no body rate
      EXPECT_LT(out.command.w_B_radps.norm(), 1e-12) << type;
    }
  }
}

// (e): an unknown type, a vehicle outside the team or a null reference throws.
TEST(TeamControllerTest, BadArgumentsThrow) {
  const CooperativeTeam team = BarTeam();
  const auto reference = MakeHoverReference(team.vehicles[0].params, kStart);
  EXPECT_THROW(MakeTeamController("geometric", team, 0, reference), std::invalid_argument);
  EXPECT_THROW(MakeTeamController("", team, 0, reference), std::invalid_argument);
  for (const std::string& type : TeamControllerNames()) {
    EXPECT_THROW(MakeTeamController(type, team, 2, reference), std::invalid_argument) << type;
    EXPECT_THROW(MakeTeamController(type, team, -1, reference), std::invalid_argument) << type;
    EXPECT_THROW(MakeTeamController(type, team, 0, nullptr), std::invalid_argument) << type;
  }
}

// The registry names both controllers, and each reports its rate: RotorTM's 100 Hz for the
// cooperative controller, the HpaMpc's own for hpa_mpc.
TEST(TeamControllerTest, NamesAndRates) {
  EXPECT_EQ(TeamControllerNames(), (std::vector<std::string>{"cooperative", "hpa_mpc"}));
  const CooperativeTeam team = BarTeam();
  const auto reference = MakeHoverReference(team.vehicles[0].params, kStart);
  EXPECT_EQ(MakeTeamController("cooperative", team, 0, reference)->RateHz(), 100.0);
  EXPECT_EQ(MakeTeamController("hpa_mpc", team, 0, reference)->RateHz(), MpcSettings().rate_hz);
}

// At the hanging layout the cooperative distribution is the payload's weight shared by the
// cables, straight up, and each cable reads taut.
TEST(TeamControllerTest, CooperativeHoverDistributesWeight) {
  const CooperativeTeam team = TriangleTeam();
  const auto reference = MakeHoverReference(team.vehicles[0].params, kStart);
  TeamPlant plant(team, CooperativeModel(team).HangingState(kStart));
  CooperativeController controller(team, 0, reference);
  const TeamView view = plant.View(0, 0.0);
  const Eigen::VectorXd mu = controller.CableForcesN(view);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int i = 0; i < 3; ++i) sum += mu.segment<3>(3 * i);
  // the sum is the weight up to rounding of a pseudo-inverse of unit-scale entries
  EXPECT_LT((sum - Eigen::Vector3d(0, 0, team.payload_mass_kg * team.gravity_mps2)).norm(), 1e-12);
  for (int i = 0; i < 3; ++i) EXPECT_GT(mu(3 * i + 2), 0.0);
  const ControlOutput out = controller.Update(view);
  EXPECT_TRUE(controller.CableTaut());
  EXPECT_EQ(out.status, ControlStatus::kSuccess);
  // the cable hangs straight down: the thrust is the vehicle's weight plus its cable's vertical
  // force (the projection xi xi^T mu drops the horizontal part), level, no body rate; up to
  // rounding
  const Params& params = team.vehicles[0].params;
  EXPECT_NEAR(out.command.thrust_N, params.quad_mass_kg * params.gravity_mps2 + mu(2), 1e-12);
  EXPECT_LT(out.command.w_B_radps.norm(), 1e-12);
}

// A vehicle below its cable's length (its cable slack) reads it slack and climbs back to its
// taut target; the team ends taut and holding the payload. Bounds: the measured final error with
// margin so a 50% regression fails.
TEST(TeamControllerTest, SlackVehicleClimbsToTaut) {
  const CooperativeTeam team = TriangleTeam();
  const auto reference = MakeHoverReference(team.vehicles[0].params, kStart);
  Eigen::VectorXd x0 = CooperativeModel(team).HangingState(kStart);
  x0(CooperativeStateIndex::Vehicle(0) + CooperativeStateIndex::kVehiclePos + 2) -= 0.2;
  for (const std::string& type : TeamControllerNames()) {
    const auto controllers = MakeTeam(type, team, reference);
    std::vector<TeamController*> raw;
    for (const auto& c : controllers) raw.push_back(c.get());
    TeamPlant plant(team, x0, {CableMode::kSlack, CableMode::kTaut, CableMode::kTaut});
    const TeamRunLog log = RunTeam(&plant, raw, kHoverS);
    ASSERT_TRUE(log.finite) << type;
    EXPECT_GT(log.slack_readings, 0) << type;
    for (TeamController* c : raw) EXPECT_TRUE(c->CableTaut()) << type;
    for (CableMode m : plant.modes()) EXPECT_EQ(m, CableMode::kTaut) << type;
    const double final_error_m = (log.p_WL_W.back() - kStart).norm();
    std::printf(
        "%s triangle slack start: final payload error %.4g m, max error %.4g m, "
        "slack readings %d\n",
        type.c_str(), final_error_m, PayloadMaxErrorM(log, *reference), log.slack_readings);
    EXPECT_LT(final_error_m, type == "cooperative" ? 1.8e-4 : 1.6e-4) << type;
  }
}

// The offset reference: the payload's reference at the attachment point, with the flat output
// for this cable's length (straight above at hover; along the wrapped cable direction in motion).
TEST(TeamControllerTest, OffsetReferenceRescalesFlatOutput) {
  const Params params = DefaultParams();
  const auto line = MakeLineReference(params, kStart, kEnd, kLineS);
  const Eigen::Vector3d offset(0.1, -0.2, 0.01);
  const double l_m = 0.8;
  const auto shifted = MakeOffsetReference(line, offset, l_m);
  Params longer = params;
  longer.cable_length_m = l_m;
  for (const double t_s : {0.0, 1.0, 2.0, 3.3}) {
    const ReferencePoint a = shifted->At(t_s);
    const ReferencePoint b =
        MakeLineReference(longer, kStart + offset, kEnd + offset, kLineS)->At(t_s);
    // the same flat output as a reference built for the longer cable at the attachment, up to
    // rounding of the rescaling
    EXPECT_LT((a.p_WL_W - b.p_WL_W).norm(), 1e-12);
    EXPECT_LT((a.p_WQ_W - b.p_WQ_W).norm(), 1e-12);
    EXPECT_LT((a.v_WQ_W - b.v_WQ_W).norm(), 1e-12);
    EXPECT_LT((a.a_WQ_W - b.a_WQ_W).norm(), 1e-11);
    EXPECT_LT((a.xi_W - b.xi_W).norm(), 1e-12);
  }
  EXPECT_THROW(MakeOffsetReference(nullptr, offset, l_m), std::invalid_argument);
  EXPECT_THROW(MakeOffsetReference(line, offset, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace hpa
