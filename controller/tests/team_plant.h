#pragma once
// Test harness for team controllers: hpa::CooperativeModel as the plant (per-cable taut -> slack
// when a tension would go negative, slack -> taut through RotorTM's inelastic re-taut jump),
// each vehicle's own body-rate loop (MakeAutopilot, RateLoopSpec{}) at 500 Hz, and each
// vehicle's TeamController at its own rate (zero-order hold) on the runner's LockstepClock.
// No MuJoCo.

#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "hpa/autopilot/autopilot.h"
#include "hpa/controller/team_controller.h"
#include "hpa/models/cooperative_model.h"
#include "hpa/models/lockstep.h"

namespace hpa {
namespace testing_util {

/// The analytic cooperative plant with per-cable mode switching and the vehicles' rate loops.
class TeamPlant {
 public:
  /// Plant and rate-loop step (s): the rate loops' 500 Hz.
  static constexpr double kDtS = 0.002;

  /// Starts from x0 (CooperativeStateIndex layout) with the cables in `modes` (empty: all taut).
  TeamPlant(const CooperativeTeam& team, const Eigen::VectorXd& x0,
            std::vector<CableMode> modes = {})
      : model_(team), x_(x0), modes_(std::move(modes)) {
    if (modes_.empty()) modes_.assign(team.vehicles.size(), CableMode::kTaut);
    for (const CooperativeVehicle& v : team.vehicles) {
      autopilots_.push_back(MakeAutopilot(v.params, RateLoopSpec{}, 1.0 / kDtS));
    }
  }

  /// One kDtS step: each rate loop toward its vehicle's command, then the plant with the modes
  /// switched as RotorTM's guards do.
  void Step(const std::vector<BodyRateCommand>& commands) {
    using I = CooperativeStateIndex;
    const int n = model_.VehicleCount();
    Eigen::VectorXd u(4 * n);
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d w_B = x_.segment<3>(I::Vehicle(i) + I::kVehicleRate);
      u.segment<4>(4 * i) = autopilots_[i]->Update(commands[i], w_B).w_cmd_radps;
    }
    // taut -> slack: a cable whose tension would be negative (again with the others' new modes)
    for (int pass = 0; pass < n; ++pass) {
      const Eigen::VectorXd tensions_N = model_.CableTensionsN(x_, u, modes_);
      bool changed = false;
      for (int i = 0; i < n; ++i) {
        if (modes_[i] == CableMode::kTaut && tensions_N(i) < 0.0) {
          modes_[i] = CableMode::kSlack;
          changed = true;
        }
      }
      if (!changed) break;
    }
    x_ = model_.Step(x_, u, modes_, kDtS);
    // slack -> taut: a slack cable reaching its length while stretching, through the jump
    const std::vector<bool> retauting = model_.RetautingCables(x_);
    bool any_slack_retauts = false;
    for (int i = 0; i < n; ++i) any_slack_retauts |= retauting[i] && modes_[i] == CableMode::kSlack;
    if (any_slack_retauts) {
      x_ = model_.RetautCollision(x_, retauting);
      for (int i = 0; i < n; ++i) {
        if (retauting[i]) modes_[i] = CableMode::kTaut;
      }
    }
  }

  /// What vehicle i's flight code knows at t_s (the true state).
  TeamView View(int i, double t_s) const {
    using I = CooperativeStateIndex;
    TeamView v;
    v.time_s = t_s;
    const int b = I::Vehicle(i);
    v.p_WQ_W = x_.segment<3>(b + I::kVehiclePos);
    v.v_WQ_W = x_.segment<3>(b + I::kVehicleVel);
    v.q_WB = Eigen::Quaterniond(x_(b + I::kVehicleQuat), x_(b + I::kVehicleQuat + 1),
                                x_(b + I::kVehicleQuat + 2), x_(b + I::kVehicleQuat + 3));
    v.w_B = x_.segment<3>(b + I::kVehicleRate);
    v.p_WL_W = x_.segment<3>(I::kPayloadPos);
    v.v_WL_W = x_.segment<3>(I::kPayloadVel);
    v.q_WP = Eigen::Quaterniond(x_(I::kPayloadQuat), x_(I::kPayloadQuat + 1),
                                x_(I::kPayloadQuat + 2), x_(I::kPayloadQuat + 3));
    v.w_P = x_.segment<3>(I::kPayloadRate);
    return v;
  }

  /// The cooperative state now.
  const Eigen::VectorXd& x() const { return x_; }
  /// Each cable's mode now.
  const std::vector<CableMode>& modes() const { return modes_; }
  /// The plant's model.
  const CooperativeModel& model() const { return model_; }

 private:
  CooperativeModel model_;
  Eigen::VectorXd x_;                                   // cooperative state  (13 (N + 1))
  std::vector<CableMode> modes_;                        // one per cable
  std::vector<std::unique_ptr<Autopilot>> autopilots_;  // one per vehicle
};

/// What a team run produced, sampled at every plant step.
struct TeamRunLog {
  std::vector<double> t_s;               // plant step times
  std::vector<Eigen::Vector3d> p_WL_W;   // payload position at each step  (3)
  std::vector<Eigen::Quaterniond> q_WP;  // payload attitude at each step
  std::vector<ControlStatus> statuses;   // every controller update's status
  int slack_readings = 0;                // updates where a controller read its cable slack
  int slack_plant_steps = 0;             // plant steps with some cable slack
  bool finite = true;                    // plant stayed finite
};

/// Flies the team for duration_s: each controller at its RateHz (fires on the first tick at or
/// after each of its periods), its command held between updates.
inline TeamRunLog RunTeam(TeamPlant* plant, const std::vector<TeamController*>& controllers,
                          double duration_s) {
  const int n = static_cast<int>(controllers.size());
  LockstepClock clock(1.0 / TeamPlant::kDtS);
  std::vector<int> loops;
  for (int i = 0; i < n; ++i) {
    loops.push_back(clock.AddLoop("control" + std::to_string(i), controllers[i]->RateHz(),
                                  TickRounding::kAtOrAfter));
  }
  std::vector<BodyRateCommand> commands(n);
  TeamRunLog log;
  const int steps = static_cast<int>(std::lround(duration_s / TeamPlant::kDtS));
  for (int k = 0; k < steps; ++k, clock.Advance()) {
    const double t = k * TeamPlant::kDtS;
    clock.BeginTick();
    for (int i = 0; i < n; ++i) {
      if (!clock.Fires(loops[i])) continue;
      const ControlOutput out = controllers[i]->Update(plant->View(i, t));
      commands[i] = out.command;
      log.statuses.push_back(out.status);
      if (!controllers[i]->CableTaut()) ++log.slack_readings;
    }
    const TeamView view = plant->View(0, t);
    log.t_s.push_back(t);
    log.p_WL_W.push_back(view.p_WL_W);
    log.q_WP.push_back(view.q_WP);
    plant->Step(commands);
    for (CableMode m : plant->modes()) {
      if (m == CableMode::kSlack) {
        ++log.slack_plant_steps;
        break;
      }
    }
    if (!plant->x().allFinite()) {
      log.finite = false;
      break;
    }
  }
  return log;
}

/// RMSE (m) of the payload's position against the reference over the whole run.
inline double PayloadRmseM(const TeamRunLog& log, const Reference& reference) {
  double sum = 0.0;
  for (size_t k = 0; k < log.t_s.size(); ++k) {
    sum += (log.p_WL_W[k] - reference.At(log.t_s[k]).p_WL_W).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(std::max<size_t>(log.t_s.size(), 1)));
}

/// Largest payload position error (m) against the reference over the run.
inline double PayloadMaxErrorM(const TeamRunLog& log, const Reference& reference) {
  double worst = 0.0;
  for (size_t k = 0; k < log.t_s.size(); ++k) {
    worst = std::max(worst, (log.p_WL_W[k] - reference.At(log.t_s[k]).p_WL_W).norm());
  }
  return worst;
}

/// Largest payload tilt (rad) over the run.
inline double PayloadMaxTiltRad(const TeamRunLog& log) {
  double worst = 0.0;
  for (const Eigen::Quaterniond& q : log.q_WP) {
    const double cos_tilt = q.normalized().toRotationMatrix()(2, 2);
    worst = std::max(worst, std::acos(std::min(1.0, std::max(-1.0, cos_tilt))));
  }
  return worst;
}

}  // namespace testing_util
}  // namespace hpa
