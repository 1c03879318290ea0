#include "hpa/controller/hpa_mpc.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include "hpa/controller/controller_registry.h"
#include "hpa/controller/rti_solver.h"

namespace hpa {

HpaMpc::HpaMpc(const Params& params, std::shared_ptr<const Reference> reference,
               const MpcSettings& settings)
    : params_(params),
      model_(std::make_shared<const HybridModel>(params)),
      reference_(std::move(reference)),
      settings_(settings),
      solver_(MakeOcpSolver(settings_.solver, settings_.solvers)) {
  if (settings_.rate_output_stage < 0 || settings_.rate_output_stage > kOcpHorizonSteps ||
      settings_.thrust_output_stage < 0 || settings_.thrust_output_stage >= kOcpHorizonSteps) {
    throw std::invalid_argument("mpc output_stage outside the horizon");
  }
  if (!reference_) throw std::invalid_argument("mpc: null reference");
}

HpaMpc::HpaMpc(const HpaMpc& other)
    : params_(other.params_),
      model_(other.model_),
      reference_(other.reference_),
      settings_(other.settings_),
      solver_(other.solver_->Clone()),
      plan_u_(other.plan_u_),
      plan_x_(other.plan_x_),
      plan_time_s_(other.plan_time_s_),
      guess_(other.guess_),
      ocp_(other.ocp_),
      solution_(other.solution_) {}

HpaMpc& HpaMpc::operator=(const HpaMpc& other) {
  if (this != &other) *this = HpaMpc(other);
  return *this;
}

void HpaMpc::Reset() {
  plan_u_.clear();
  plan_x_.clear();
}

Ocp HpaMpc::BuildProblem(const SystemState& state, const std::vector<InputVector>& guess) const {
  Ocp ocp;
  BuildProblem(state, guess, &ocp);
  return ocp;
}

void HpaMpc::BuildProblem(const SystemState& state, const std::vector<InputVector>& guess,
                          Ocp* ocp) const {
  const CableMode mode = settings_.hybrid ? state.mode : CableMode::kTaut;
  // a lost payload (hybrid only: the paper's baseline has no such notion): the quadrotor is
  // held on its reference, as in slack, and no cost looks at the guessed payload; a supported
  // one lost from view is still looked for where the estimator carries it
  const bool lost = settings_.hybrid && state.payload_lost && !state.payload_supported;
  const double perception = settings_.hybrid && !lost ? settings_.perception_weight : 0.0;
  OcpWeights weights = settings_.weights;
  if (lost) weights.q_load = weights.q_quad;
  BuildOcp(model_, *reference_, state.time_s, mode, perception, weights, ocp);
  ocp->payload_supported = mode == CableMode::kSlack && state.payload_supported;
  SetCameraDeadzone(state, ocp);
  const bool slack_plan = settings_.hybrid && mode == CableMode::kSlack && !lost;
  if (!slack_plan) return;
  // the plan the slack horizon is predicted along: the caller's guess, else the warm start
  std::vector<InputVector> warm;
  if (guess.empty()) warm = WarmStart(state.time_s);
  const std::vector<InputVector>& plan = guess.empty() ? warm : guess;
  const StateVector x0 = state.ToVector();
  if (settings_.predict_retaut) {
    // the mode sequence is fixed for the solve: where the plan meets the guard
    const int stage = PredictRetautStage(*ocp, x0, plan);
    if (stage > 0) ScheduleRetaut(*reference_, state.time_s, stage, ocp);
  }
  // the slack camera term per stage, from that stage's predicted payload
  if (perception > 0.0) SetCameraDeadzonesAlong(x0, plan, ocp);
}

std::vector<InputVector> HpaMpc::WarmStart(double t_s) const {
  std::vector<InputVector> u;
  WarmStart(t_s, &u);
  return u;
}

void HpaMpc::WarmStart(double t_s, std::vector<InputVector>* u) const {
  const int n = kOcpHorizonSteps;
  const double dt = kOcpStageDtS;
  const double elapsed_s = t_s - plan_time_s_;
  if (plan_u_.size() != static_cast<size_t>(n) || !std::isfinite(elapsed_s) || elapsed_s < 0.0 ||
      elapsed_s > n * dt) {
    u->assign(n, InputVector::Constant(params_.HoverMotorSpeedRadps()));
    return;
  }
  u->resize(n);
  for (int k = 0; k < n; ++k) {
    const double tau = (k * dt + elapsed_s) / dt;  // position in the old plan, in stages
    const int i = static_cast<int>(std::floor(tau));
    if (i >= n - 1) {
      (*u)[k] = plan_u_[n - 1];
    } else {
      const double frac = tau - i;
      (*u)[k] = (1.0 - frac) * plan_u_[i] + frac * plan_u_[i + 1];
    }
  }
}

BodyRateCommand HpaMpc::CommandFromPlan() const {
  BodyRateCommand cmd;
  cmd.w_B_radps = plan_x_[settings_.rate_output_stage].segment<3>(StateIndex::kBodyRate);
  cmd.thrust_N = params_.k_f_N_per_radps2 * plan_u_[settings_.thrust_output_stage].squaredNorm();
  return cmd;
}

bool HpaMpc::RecoveryCommand(const SystemState& state, BodyRateCommand* command) const {
  // Outside the envelope the plan can be flown in, recover attitude first and plan afresh after:
  // - tumbling faster than the stage model resolves (a 0.1 s stage of piecewise-constant rotor
  //   speeds turns a plan at this rate through more than a radian, so its stage-1 body rate is
  //   no command);
  // - tilted beyond the recovery tilt: a plan there cuts collective thrust, and a rate loop
  //   without airmode (PX4's default) then has no moment left to level the vehicle.
  // The recovery is PX4's attitude loop toward level (body rate = MC_ROLL_P x the tilt error,
  // yaw left alone) at hover thrust, which leaves the rotors the moment to fly it.
  const Eigen::Vector3d z_B_W = state.q_WB * Eigen::Vector3d::UnitZ();
  const double tilt_rad = std::acos(std::clamp(z_B_W.z(), -1.0, 1.0));
  const bool tumbling = settings_.recovery_body_rate_radps > 0.0 &&
                        state.w_B.norm() > settings_.recovery_body_rate_radps;
  const bool tipped = settings_.recovery_tilt_rad > 0.0 && tilt_rad > settings_.recovery_tilt_rad;
  if (!tumbling && !tipped) return false;
  *command = LevelOutCommand(params_, state.q_WB, settings_.recovery_attitude_gain_per_s);
  return true;
}

StateVector HpaMpc::InitialState(const SystemState& state, const Ocp& ocp) const {
  // the taut flow holds on the taut manifold only: hpa_mpc projects x0 onto it (jump map);
  // nonhybrid_mpc starts from the state as measured, as the paper's baseline does
  StateVector x0 = ocp.mode == CableMode::kTaut && settings_.hybrid
                       ? model_->ProjectToTaut(state.ToVector())
                       : state.ToVector();
  if (ocp.mode == CableMode::kTaut && settings_.hybrid && state.payload_lost) {
    // a lost payload on a taut cable: what is still known is that it hangs on the cable; the
    // taut model predicts with it at rest below the quadrotor
    x0.segment<3>(StateIndex::kPayloadPos) =
        state.p_WQ_W - Eigen::Vector3d(0, 0, params_.cable_length_m);
    x0.segment<3>(StateIndex::kPayloadVel) = state.v_WQ_W;
  }
  return x0;
}

ControlOutput HpaMpc::Update(const SystemState& state) {
  const auto start = std::chrono::steady_clock::now();
  ControlOutput out;
  const auto finish = [&start, &out]() {
    out.solve_time_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return out;
  };
  // non-finite state: level out at hover thrust (on the attitude if it is finite), plan kept
  if (!state.AllFinite() || !std::isfinite(state.time_s)) {
    out.status = ControlStatus::kNonFinite;
    out.command = LevelOutCommand(params_, state.q_WB, settings_.recovery_attitude_gain_per_s);
    return finish();
  }
  if (RecoveryCommand(state, &out.command)) {
    Reset();
    out.status = ControlStatus::kRecovery;
    return finish();
  }

  // the scratch members keep their memory from call to call (no allocation in steady state)
  WarmStart(state.time_s, &guess_);
  BuildProblem(state, guess_, &ocp_);
  const StateVector x0 = InitialState(state, ocp_);
  const bool had_plan = plan_u_.size() == static_cast<size_t>(ocp_.horizon_steps);

  solver_->SolveInto(ocp_, x0, guess_, &solution_);
  const ControlStatus status = solution_.status;
  const bool solved = status == ControlStatus::kSuccess || status == ControlStatus::kMaxIterations;
  if (!solved) {
    // fallback 1: the previous plan shifted; fallback 2: level out at hover thrust
    solution_.u = guess_;
    solution_.cost = OcpCost(ocp_, x0, solution_.u, &solution_.x);
    bool usable = had_plan && std::isfinite(solution_.cost);
    for (const StateVector& xi : solution_.x) usable = usable && xi.allFinite();
    if (!usable) {
      Reset();
      out.status = ControlStatus::kFallback;
      out.command = LevelOutCommand(params_, state.q_WB, settings_.recovery_attitude_gain_per_s);
      return finish();
    }
  }
  plan_u_.swap(solution_.u);
  plan_x_.swap(solution_.x);
  plan_time_s_ = state.time_s;
  out.status = status;
  out.cost = solution_.cost;
  out.command = CommandFromPlan();
  return finish();
}

namespace {

// The settings both MPCs read: which solver, and how RTI solves its QP.
std::vector<SettingDecl> SolverSettings() {
  return {{"solver", "", std::string("rti"), 0.0, 0.0, OcpSolverNames,
           "the OCP solver: a registered solver (hpa schema lists them)"},
          {"qp_method", "", std::string("structured"), 0.0, 0.0, RtiQpMethodNames,
           "how the rti solver solves its QP (the other solvers ignore it)"}};
}

// An MPC controller from its scenario settings: hybrid (hpa_mpc, perception cost and the re-taut
// prediction as configured) or not (nonhybrid_mpc: always taut, neither).
std::unique_ptr<Controller> MakeMpcController(const ControllerConfig& config, const Params& params,
                                              std::shared_ptr<const Reference> reference,
                                              bool hybrid) {
  MpcSettings settings;
  settings.hybrid = hybrid;
  if (hybrid) {
    settings.perception_weight = config.Number("perception_weight");
    settings.predict_retaut = config.Switch("predict_retaut");
  }
  settings.solver = config.Name("solver");
  settings.solvers.rti.qp_method = ParseRtiQpMethod(config.Name("qp_method"));
  return std::make_unique<HpaMpc>(params, std::move(reference), settings);
}

}  // namespace

std::vector<SettingDecl> HpaMpcSettings() {
  std::vector<SettingDecl> settings{
      {"perception_weight", "-", kDefaultPerceptionWeight, 0.0, 1e3, nullptr,
       "scale on the tuned L_cam weights (1: as tuned, 0: L_cam off)"},
      {"predict_retaut", "", false, 0.0, 0.0, nullptr,
       "predict the slack-to-taut guard in the horizon (false: slack held, the paper's form)"}};
  for (SettingDecl& d : SolverSettings()) settings.push_back(std::move(d));
  return settings;
}

std::vector<SettingDecl> NonhybridMpcSettings() { return SolverSettings(); }

std::unique_ptr<Controller> MakeHpaMpcController(const ControllerConfig& config,
                                                 const Params& params,
                                                 std::shared_ptr<const Reference> reference) {
  return MakeMpcController(config, params, std::move(reference), true);
}

std::unique_ptr<Controller> MakeNonhybridMpcController(const ControllerConfig& config,
                                                       const Params& params,
                                                       std::shared_ptr<const Reference> reference) {
  return MakeMpcController(config, params, std::move(reference), false);
}

}  // namespace hpa
