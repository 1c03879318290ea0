#pragma once
// Test harness: hpa::HybridModel as the plant (with taut/slack switching and the inelastic
// re-taut jump of docs/design.md section 4), the body-rate controller at 500 Hz and a high-level
// Controller at its own rate, on the runner's LockstepClock. No MuJoCo (the scenario tests add it).

#include <cmath>
#include <functional>
#include <vector>

#include "hpa/autopilot/body_rate_controller.h"
#include "hpa/controller/controller.h"
#include "hpa/controller/ocp.h"
#include "hpa/models/hybrid_model.h"
#include "hpa/models/lockstep.h"

namespace hpa {
namespace testing_util {

/// The analytic plant with mode switching.
class HybridPlant {
 public:
  HybridPlant(const Params& params, const StateVector& x0, CableMode mode)
      : params_(params), model_(params), x_(x0), mode_(mode) {}

  /// Advances dt_s with rotor speeds u; switches taut -> slack when the tension would be
  /// negative, slack -> taut (inelastic jump) when the cable reaches its length and stretches.
  void Step(const InputVector& u, double dt_s) {
    using I = StateIndex;
    if (mode_ == CableMode::kTaut && model_.TautTensionN(x_, u) < 0.0) mode_ = CableMode::kSlack;
    x_ = model_.Step(x_, u, mode_, dt_s);
    if (mode_ == CableMode::kSlack) {
      const Eigen::Vector3d r = x_.segment<3>(I::kPayloadPos) - x_.segment<3>(I::kQuadPos);
      const Eigen::Vector3d xi = r.normalized();
      const Eigen::Vector3d v_l = x_.segment<3>(I::kPayloadVel);
      const Eigen::Vector3d v_q = x_.segment<3>(I::kQuadVel);
      if (r.norm() >= params_.cable_length_m && (v_l - v_q).dot(xi) > 0.0) {
        const double m = params_.quad_mass_kg, m_l = params_.payload_mass_kg;
        const double v_c = (m * v_q.dot(xi) + m_l * v_l.dot(xi)) / (m + m_l);
        x_.segment<3>(I::kQuadVel) = v_q + (v_c - v_q.dot(xi)) * xi;
        x_.segment<3>(I::kPayloadVel) = v_l + (v_c - v_l.dot(xi)) * xi;
        x_.segment<3>(I::kPayloadPos) = x_.segment<3>(I::kQuadPos) + params_.cable_length_m * xi;
        mode_ = CableMode::kTaut;
      }
    }
  }

  /// True state as the flight code's message.
  SystemState State(double t_s) const {
    SystemState s;
    s.FromVector(x_);
    s.time_s = t_s;
    s.mode = mode_;
    return s;
  }
  const StateVector& x() const { return x_; }
  CableMode mode() const { return mode_; }

 private:
  Params params_;
  HybridModel model_;
  StateVector x_;
  CableMode mode_;
};

/// What a closed-loop run produced.
struct ClosedLoopLog {
  std::vector<double> t_s;             // controller update times
  std::vector<SystemState> states;     // true state at each update
  std::vector<ControlOutput> outputs;  // controller outputs
  bool finite = true;                  // plant stayed finite
  double max_solve_ms = 0.0;
};

/// Runs `controller` on the plant for duration_s: plant and rate loop at 500 Hz (2 ms), the
/// controller at its RateHz (zero-order hold). `event(t, plant)` may kick the plant.
inline ClosedLoopLog RunClosedLoop(const Params& params, Controller* controller, HybridPlant* plant,
                                   double duration_s,
                                   const std::function<void(double, HybridPlant*)>& event = {}) {
  constexpr double kDtS = 0.002;
  BodyRateController rate_loop(params);
  ClosedLoopLog log;
  const int steps = static_cast<int>(std::lround(duration_s / kDtS));
  // the runner's lockstep clock, ticking with the plant; the controller fires on the first tick
  // at or after each of its periods
  LockstepClock clock(1.0 / kDtS);
  const int control_loop = clock.AddLoop("control", controller->RateHz(), TickRounding::kAtOrAfter);
  BodyRateCommand cmd;
  for (int i = 0; i < steps; ++i, clock.Advance()) {
    const double t = i * kDtS;
    if (event) event(t, plant);
    clock.BeginTick();
    if (clock.Fires(control_loop)) {
      const SystemState s = plant->State(t);
      const ControlOutput out = controller->Update(s);
      cmd = out.command;
      log.t_s.push_back(t);
      log.states.push_back(s);
      log.outputs.push_back(out);
      log.max_solve_ms = std::max(log.max_solve_ms, out.solve_time_ms);
    }
    const SystemState s = plant->State(t);
    const InputVector u = rate_loop.Update(cmd, s.w_B, kDtS);
    plant->Step(u, kDtS);
    if (!plant->x().allFinite()) {
      log.finite = false;
      break;
    }
  }
  return log;
}

/// Per-axis RMSE of the payload against the reference over updates with t >= from_s.
inline Eigen::Vector3d PayloadRmse(const ClosedLoopLog& log, const Reference& reference,
                                   double from_s) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int count = 0;
  for (size_t i = 0; i < log.states.size(); ++i) {
    if (log.t_s[i] < from_s) continue;
    const Eigen::Vector3d e = log.states[i].p_WL_W - reference.At(log.t_s[i]).p_WL_W;
    sum += e.cwiseAbs2();
    ++count;
  }
  return (sum / std::max(count, 1)).cwiseSqrt();
}

}  // namespace testing_util
}  // namespace hpa
