#pragma once
// HPA-MPC (hybrid: mode from SystemState::mode, perception cost on) and its non-hybrid
// baseline (always-taut model, payload cost, no perception cost) as Controllers.

#include <memory>
#include <string>
#include <vector>

#include "hpa/controller/controller.h"
#include "hpa/controller/ocp.h"
#include "hpa/controller/ocp_solver.h"
#include "hpa/models/hybrid_model.h"

namespace hpa {

/// Settings of an MPC controller.
struct MpcSettings {
  bool hybrid = true;  // false: nonhybrid_mpc (always taut, no perception cost)
  double perception_weight = kDefaultPerceptionWeight;  // scale on q_cam (hybrid)
  std::string solver = "rti";  // a name from OcpSolvers(): rti | nlopt
  OcpWeights weights = OcpWeights::Tuned();
  OcpSolverSettings solvers;    // settings of the solver named by `solver`
  int rate_output_stage = 1;    // body rates flown: plan state x[1] (the paper's second stage)
  int thrust_output_stage = 0;  // thrust flown: plan input u[0] (why not u[1]: README)
  double rate_hz = 150.0;       // rate the runner calls Update at
  // Hybrid only, in slack mode: predict the slack-to-taut guard inside the horizon from the warm
  // start and switch to the taut model there, through the jump map (PredictRetautStage). false:
  // slack held over the whole horizon (the paper).
  bool predict_retaut = false;
  // Recovery instead of a plan (both MPCs), status kRecovery: above this body rate (norm) one
  // 0.1 s stage turns the vehicle by more than a radian, which the stage model cannot resolve;
  // 0 = never.
  double recovery_body_rate_radps = 10.0;
  // ... or above this tilt. Ours: 1.5 x PX4's MPC_TILTMAX_AIR default (45 deg), the most PX4's
  // own position loop commands; 0 = never
  double recovery_tilt_rad = 67.5 * M_PI / 180.0;
  // the recovery's and the fallbacks' attitude gain (LevelOutCommand)
  double recovery_attitude_gain_per_s = kPx4AttitudeGainPerS;
};

/// Model predictive controller over the OCP of ocp.h.
class HpaMpc : public Controller {
 public:
  /// Throws std::invalid_argument for an unknown solver or a bad perception weight.
  HpaMpc(const Params& params, std::shared_ptr<const Reference> reference,
         const MpcSettings& settings);
  /// Copies plan, settings and a clone of the solver.
  HpaMpc(const HpaMpc& other);
  /// Copy-assigns plan, settings and a clone of the solver.
  HpaMpc& operator=(const HpaMpc& other);
  /// Moves (the moved-from controller has no solver and must not be updated).
  HpaMpc(HpaMpc&&) noexcept = default;
  /// Move-assigns, as the move constructor.
  HpaMpc& operator=(HpaMpc&&) noexcept = default;

  /// One solve of the solver named by settings.solver, warm-started from the previous plan; always
  /// a safe command: non-finite state -> kNonFinite + a level-out at hover thrust
  /// (LevelOutCommand); body rate or tilt beyond the recovery settings -> kRecovery, the same
  /// level-out; solver failure -> previous plan shifted (kQpFailure), or the level-out
  /// (kFallback) when there is no usable plan.
  ControlOutput Update(const SystemState& state) override;
  /// Rate the runner calls Update at (MpcSettings::rate_hz).
  double RateHz() const override { return settings_.rate_hz; }

  /// Warm start for time t_s: the previous plan shifted by the elapsed time (linear
  /// interpolation between stages, last input held; exactly one stage when dt has passed),
  /// or hover speeds when there is no plan.
  std::vector<InputVector> WarmStart(double t_s) const;
  /// WarmStart into `u`, reusing its memory.
  void WarmStart(double t_s, std::vector<InputVector>* u) const;

  /// The OCP this controller would solve for `state` (mode and perception per settings), with
  /// the re-taut predicted from x0 under `guess` when settings.predict_retaut (empty guess: the
  /// warm start at state.time_s).
  Ocp BuildProblem(const SystemState& state, const std::vector<InputVector>& guess = {}) const;
  /// BuildProblem into `ocp`, reusing its vectors' memory.
  void BuildProblem(const SystemState& state, const std::vector<InputVector>& guess,
                    Ocp* ocp) const;

  /// Current plan inputs (empty before the first successful Update).  (N)
  const std::vector<InputVector>& plan_inputs() const { return plan_u_; }
  /// States of the current plan, simulated from its x0.  (N + 1)
  const std::vector<StateVector>& plan_states() const { return plan_x_; }
  /// Forgets the plan (next call starts from hover).
  void Reset();

  /// The settings this controller was made with.
  const MpcSettings& settings() const { return settings_; }
  /// The hybrid model its OCPs predict with.
  const HybridModel& model() const { return *model_; }

 private:
  BodyRateCommand CommandFromPlan() const;
  // The attitude-recovery command when the state is outside the envelope a plan can fly in
  // (tumbling or tipped per the recovery settings); false when inside it.
  bool RecoveryCommand(const SystemState& state, BodyRateCommand* command) const;
  // The OCP's x0 for `state`: projected onto the cable in taut hybrid mode, lost payload placed.
  StateVector InitialState(const SystemState& state, const Ocp& ocp) const;

  Params params_;
  std::shared_ptr<const HybridModel> model_;  // the OCPs' dynamics
  std::shared_ptr<const Reference> reference_;
  MpcSettings settings_;
  std::unique_ptr<OcpSolver> solver_;  // made from the registry by settings_.solver
  std::vector<InputVector> plan_u_;    // (N)
  std::vector<StateVector> plan_x_;    // (N + 1)
  double plan_time_s_ = 0.0;           // time of plan stage 0
  // scratch of Update, kept so a steady-state update reuses its memory
  std::vector<InputVector> guess_;  // warm start  (N)
  Ocp ocp_;                         // the problem solved
  OcpSolution solution_;            // the solver's answer; swapped with the plan
};

}  // namespace hpa
