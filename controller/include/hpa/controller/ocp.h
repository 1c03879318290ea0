#pragma once
// The HPA-MPC optimal control problem as a plain struct (OCS2 habit): horizon, mode held over
// the horizon, dynamics, state/input references, weights. Any solver (RTI, NLopt) takes it.
//
// Cost, a sum of squared residuals: J = sum_{k<N} |r_k(x_k, u_k)|^2 + |r_N(x_N)|^2, where r_k
// stacks the named terms of OcpTerms() (MJPC's weighted residual terms): state tracking
// (m L_load + (1 - m) L_quad), input, perception L_cam, soft tilt, soft body rate. Every term
// is sqrt(diagonal weight) times its error. Rotor-speed bounds are hard box constraints of the
// solvers; tilt and body-rate limits are SOFT: one-sided penalties w max(0, h(x))^2.

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

#include "hpa/controller/controller.h"
#include "hpa/controller/reference.h"
#include "hpa/models/hybrid_model.h"
#include "hpa/models/params.h"
#include "hpa/models/state.h"

namespace hpa {

constexpr int kOcpHorizonSteps = 10;  // N
constexpr double kOcpStageDtS = 0.1;  // s per stage: horizon 1 s
// Rows of the stage residual: the sum of the rows of OcpTerms() (checked by a static_assert in
// ocp_terms.cc). Fixed at compile time so the Gauss-Newton products use fixed-size Eigen kernels.
constexpr int kNr = 29;

using ResidualVector = Eigen::Matrix<double, kNr, 1>;
using ResidualStateJacobian = Eigen::Matrix<double, kNr, kNx>;
using ResidualInputJacobian = Eigen::Matrix<double, kNr, kNu>;

/// Diagonal weights of the stage cost (the tuned values: OcpWeights::Tuned, history in
/// controller/README.md).
struct OcpWeights {
  StateVector q_load;            // L_load: taut mode, on x - x_ref  (19)
  StateVector q_quad;            // L_quad: slack mode, on x - x_ref; payload entries zero  (19)
  InputVector r_input;           // on (u - u_ref) / u_hover, dimensionless  (4)
  Eigen::Vector2d q_cam_per_m2;  // L_cam in taut mode, on the x, y of p_C (m)  (2)
  Eigen::Vector2d q_cam_slack_per_m2;  // L_cam in slack mode (both x perception_weight)  (2)
  // L_cam's camera attitude: true -> the stage's reference attitude (L_cam is then a cost on
  // positions only, the default), false -> the state's attitude (the paper's literal form).
  bool cam_at_reference_attitude = true;
  // Slack-mode L_cam penalises only the part of the payload's image offset beyond this
  // fraction of the half field of view (per axis, a dead zone). 0 = the paper's plain quadratic.
  double cam_slack_deadzone_fraction = 0.0;
  // The same for a held payload (Ocp::payload_supported): it moves only as the hand moves it,
  // so the vehicle can follow it closely; a free one swings and falls, and a tight zone would
  // chase every swing.
  double cam_held_deadzone_fraction = 0.0;
  double terminal_factor = 1.0;      // terminal state weights = factor * stage state weights
  double tilt_max_rad = 0.0;         // soft limit on the angle between body z and world z
  double tilt_weight = 0.0;          // weight on max(0, (1 - cos tilt) - (1 - cos tilt_max))^2
  double body_rate_max_radps = 0.0;  // soft limit on each |w_B|
  double body_rate_weight = 0.0;     // weight on max(0, |w_i| - max)^2, (rad/s)^-2

  /// The tuned weights (values in ocp.cc, why in controller/README.md "Tuning history").
  static OcpWeights Tuned();
};

/// The perception weight (scale on the tuned L_cam) an MPC flies unless its scenario says
/// otherwise: L_cam as tuned.
constexpr double kDefaultPerceptionWeight = 1.0;

/// One instance of the optimal control problem: dynamics, references, weights, bounds.
struct Ocp {
  std::shared_ptr<const HybridModel> model;  // dynamics F and its Jacobians (set by BuildOcp)
  int horizon_steps = kOcpHorizonSteps;      // N
  double stage_dt_s = kOcpStageDtS;          // stage length
  CableMode mode = CableMode::kTaut;         // mode at stage 0, held up to retaut_stage
  // A re-taut predicted inside the horizon (controller.predict_retaut): stages k >= retaut_stage
  // are taut, and the jump map (HybridModel::ProjectToTaut) is applied to the state entering
  // stage retaut_stage. -1: `mode` is held over the whole horizon (the paper's form).
  int retaut_stage = -1;
  double perception_weight = kDefaultPerceptionWeight;  // scale on q_cam (0: off)
  // slack and held up (SystemState::payload_supported): L_cam sees the payload without the free
  // fall the model predicts for it (SeenPayloadOffset)
  bool payload_supported = false;
  OcpWeights weights = OcpWeights::Tuned();
  double u_hover_radps = 1.0;                          // normalisation of the input residual
  InputVector u_min_radps = InputVector::Zero();       // hard bounds  (4)
  InputVector u_max_radps = InputVector::Zero();       // hard bounds  (4)
  std::vector<StateVector> x_ref;                      // stages 0..N  (N+1)
  std::vector<InputVector> u_ref;                      // stages 0..N-1  (N)
  Eigen::Matrix3d R_BC = Eigen::Matrix3d::Identity();  // camera axes in body
  Eigen::Vector3d t_BC_B_m = Eigen::Vector3d::Zero();  // camera origin in body  (3)
  Eigen::Vector2d camera_tan_half_fov = Eigen::Vector2d::Ones();  // (W/2)/f, (H/2)/f  (2)
  // slack L_cam dead zone in metres of camera x, y, fixed for the solve from the payload's
  // current depth (the predicted free fall would otherwise widen it); infinite = no L_cam
  Eigen::Vector2d cam_slack_deadzone_m = Eigen::Vector2d::Zero();  // (2)
  // the same per stage 0..N (N+1), from each stage's predicted payload (SetCameraDeadzonesAlong);
  // empty: cam_slack_deadzone_m at every stage
  std::vector<Eigen::Vector2d> cam_slack_deadzone_stage_m;

  /// Slack L_cam dead zone (m, camera x, y) at stage k; infinite: no L_cam at that stage.
  const Eigen::Vector2d& CamSlackDeadzone(int k) const {
    return cam_slack_deadzone_stage_m.empty() ? cam_slack_deadzone_m
                                              : cam_slack_deadzone_stage_m[std::min<size_t>(
                                                    k, cam_slack_deadzone_stage_m.size() - 1)];
  }

  /// Cable mode of stage k: `mode`, or taut from retaut_stage on.
  CableMode StageMode(int k) const {
    return retaut_stage >= 0 && k >= retaut_stage ? CableMode::kTaut : mode;
  }
  /// Stage k of the dynamics: x_{k+1} = F_k(x_k, u_k) in StageMode(k), followed by the jump map
  /// when k + 1 == retaut_stage.
  StateVector Step(int k, const StateVector& x, const InputVector& u) const;
  /// F_k and its Jacobians a = dF_k/dx (19 x 19), b = dF_k/du (19 x 4), through the jump map.
  void StepJacobians(int k, const StateVector& x, const InputVector& u, StateVector* x_next,
                     StateMatrix* a, InputMatrix* b) const;
};

// --- the cost as a list of named terms -------------------------------------------------------

/// Diagonal weight or square-rooted weight of one term's rows (at most kNr rows, no heap).
using OcpTermWeight = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kNr, 1>;
/// A term's rows of the stage residual (rows).
using OcpTermResidual = Eigen::Block<ResidualVector, Eigen::Dynamic, 1>;
/// A term's rows of d r / d x (rows x 19).
using OcpTermStateJacobian = Eigen::Block<ResidualStateJacobian, Eigen::Dynamic, kNx>;
/// A term's rows of d r / d u (rows x 4).
using OcpTermInputJacobian = Eigen::Block<ResidualInputJacobian, Eigen::Dynamic, kNu>;

/// How a term enters the terminal stage N.
enum class OcpTermAtTerminal {
  kOmitted,              // not at stage N (the input term)
  kTimesTerminalFactor,  // weight x OcpWeights::terminal_factor
  kAsStage,              // same weight as the stages
};

/// Diagonal weight of a term's rows in a cable mode (taut / slack), before the stage factor.
using OcpTermWeightFunction = OcpTermWeight (*)(const OcpWeights& weights, CableMode mode);
/// Problem-level scale of a term's weight (the perception weight for L_cam).
using OcpTermScaleFunction = double (*)(const Ocp& ocp);
/// Writes the term's weighted residual sqrt_weight .* e(x, u, k) into r and, when not null,
/// its Jacobians into r_x and r_u; all three arrive zeroed. The term applies sqrt_weight itself.
using OcpTermResidualFunction = void (*)(const Ocp& ocp, int k, const StateVector& x,
                                         const InputVector& u, const OcpTermWeight& sqrt_weight,
                                         OcpTermResidual* r, OcpTermStateJacobian* r_x,
                                         OcpTermInputJacobian* r_u);

/// One named, weighted residual term of the stage cost. Its weight at stage k is
/// factor_k * scale(ocp) * weight(weights, mode), factor_k = terminal_factor at stage N for
/// kTimesTerminalFactor terms and 1 otherwise; a term with no positive weight at a stage is
/// not evaluated (its rows stay zero).
struct OcpTerm {
  std::string_view name;                                        // e.g. "perception"
  int rows = 0;                                                 // residual rows
  OcpTermAtTerminal at_terminal = OcpTermAtTerminal::kAsStage;  // role at stage N
  OcpTermWeightFunction weight = nullptr;                       // per-mode diagonal weight
  OcpTermScaleFunction scale = nullptr;                         // nullptr: no extra scale
  OcpTermResidualFunction residual = nullptr;                   // weighted residual, Jacobians
  // the columns of [x, u] the term's Jacobian rows may be nonzero in, any stage and mode: bit c
  // is state c for c < kNx, input c - kNx (OcpColumns); 0: not declared, any column
  std::uint32_t columns = 0;
  int offset = 0;  // first row in the stage residual, computed from the list order
};

/// Bit mask of `count` columns of [x, u] from `first` (a state index, or kNx + an input index).
constexpr std::uint32_t OcpColumns(int first, int count) {
  return ((std::uint32_t{1} << count) - 1) << first;
}
static_assert(kNx + kNu <= 32, "OcpTerm::columns has one bit per column of [x, u]");

/// The terms of the stage cost, in residual order (their rows add up to kNr).
const std::vector<OcpTerm>& OcpTerms();

/// Per row of the stage residual, the columns of [x, u] its Jacobian row may be nonzero in (its
/// term's OcpTerm::columns).
const std::array<std::uint32_t, kNr>& OcpResidualColumns();

/// The term named `name`, or nullptr.
const OcpTerm* FindOcpTerm(std::string_view name);

/// Diagonal weight of `term`'s rows at stage k of `ocp` (zero at stage N for kOmitted terms).
OcpTermWeight OcpTermStageWeight(const Ocp& ocp, const OcpTerm& term, int k);

/// One term's weighted residual (rows) and, if asked, its Jacobians (rows x 19, rows x 4) at
/// stage k; zero where the term is not evaluated.
void EvaluateOcpTerm(const Ocp& ocp, const OcpTerm& term, int k, const StateVector& x,
                     const InputVector& u, Eigen::VectorXd* r, Eigen::MatrixXd* r_x,
                     Eigen::MatrixXd* r_u);

// --- building the problem --------------------------------------------------------------------

/// Sets ocp->cam_slack_deadzone_m from the current state: deadzone fraction (a held payload's
/// when ocp->payload_supported, else a free one's) x tan(half FOV) x the payload's depth in the
/// camera; a payload at or above the lens plane (thrown up) cannot
/// be brought into view by moving, so the slack L_cam is switched off (infinite dead zone).
void SetCameraDeadzone(const SystemState& state, Ocp* ocp);

/// Sets ocp->cam_slack_deadzone_stage_m along the plan u from x0 (slack mode only; taut clears
/// it): stage 0 keeps cam_slack_deadzone_m, stage k the dead zone of the depth of its own
/// predicted payload as L_cam sees it (no farther than the cable's sphere, see
/// CostPayloadInCamera); where that payload is nearer the lens plane than the minimum depth, the
/// slack L_cam is off (infinite dead zone). A supported payload keeps stage 0's dead zone at every
/// stage (it stays at the depth it is held at). Fixed for the solve.
void SetCameraDeadzonesAlong(const StateVector& x0, const std::vector<InputVector>& u, Ocp* ocp);

/// First stage k (1..N) whose state, simulated from x0 with u in slack mode, has reached the
/// cable's length with the payload moving away from the quadrotor along the cable (the
/// slack-to-taut guard); -1 when the guard is not reached inside the horizon or ocp is taut.
int PredictRetautStage(const Ocp& ocp, const StateVector& x0, const std::vector<InputVector>& u);

/// Schedules a re-taut at `stage` (1..N; -1 clears it): ocp->retaut_stage, and the state and input
/// references of the stages from `stage` on rebuilt for the taut mode from `reference` at t0_s.
void ScheduleRetaut(const Reference& reference, double t0_s, int stage, Ocp* ocp);

/// Builds the OCP at time t0_s on `model`: references from `reference` at t0 + k dt, mode,
/// weights, and bounds and camera transform from model->params().
Ocp BuildOcp(std::shared_ptr<const HybridModel> model, const Reference& reference, double t0_s,
             CableMode mode, double perception_weight,
             const OcpWeights& weights = OcpWeights::Tuned());

/// BuildOcp into `ocp`, reusing its vectors (no heap allocation once they have their sizes).
void BuildOcp(std::shared_ptr<const HybridModel> model, const Reference& reference, double t0_s,
              CableMode mode, double perception_weight, const OcpWeights& weights, Ocp* ocp);

/// BuildOcp on a HybridModel of its own made from params.
Ocp BuildOcp(const Params& params, const Reference& reference, double t0_s, CableMode mode,
             double perception_weight, const OcpWeights& weights = OcpWeights::Tuned());

/// State reference of one reference point: payload and flat quadrotor position/velocity,
/// attitude whose body z is the thrust direction of `mode` (yaw 0), zero body rate.
StateVector StateReference(const Params& params, const ReferencePoint& point, CableMode mode);

/// Rotor speeds (all equal) giving the collective thrust the reference point needs in `mode`.
InputVector InputReference(const Params& params, const ReferencePoint& point, CableMode mode);

/// Camera-frame payload position p_C = (R R_BC)^T (x_L - x_Q - R t_BC) of a state.
Eigen::Vector3d PayloadInCamera(const Ocp& ocp, const StateVector& x);

/// The p_C that L_cam penalises at stage k: PayloadInCamera, with R the reference attitude of
/// stage k when weights.cam_at_reference_attitude (the default), else the state's. In a slack
/// stage a predicted payload beyond the cable's length l is taken on the cable's sphere in its
/// direction (x_Q + l (x_L - x_Q) / |x_L - x_Q|): the free fall cannot carry it further.
Eigen::Vector3d CostPayloadInCamera(const Ocp& ocp, int k, const StateVector& x);

// --- evaluating the problem ------------------------------------------------------------------

/// Residual of stage k (k = N: terminal, u ignored) stacked from OcpTerms() and, if asked, its
/// Jacobians. Stage cost = r.squaredNorm().
void StageResidual(const Ocp& ocp, int k, const StateVector& x, const InputVector& u,
                   ResidualVector* r, ResidualStateJacobian* r_x, ResidualInputJacobian* r_u);

/// Simulates u from x0 with the OCP's dynamics and returns the cost; x_traj (N+1) if not null.
double OcpCost(const Ocp& ocp, const StateVector& x0, const std::vector<InputVector>& u,
               std::vector<StateVector>* x_traj = nullptr);

/// The OCP linearised along the trajectory simulated from x0 with u (single shooting): what
/// the RTI QP and the adjoint gradient are both built from.
struct OcpLinearization {
  std::vector<StateVector> x;              // simulated states  (N + 1)
  std::vector<StateMatrix> a;              // dF/dx at each stage  (N, 19 x 19)
  std::vector<InputMatrix> b;              // dF/du at each stage  (N, 19 x 4)
  std::vector<ResidualVector> r;           // stage residuals, r[N] terminal  (N + 1, 29)
  std::vector<ResidualStateJacobian> r_x;  // d r_k / d x_k  (N + 1, 29 x 19)
  std::vector<ResidualInputJacobian> r_u;  // d r_k / d u_k; r_u[N] = 0  (N + 1, 29 x 4)
  double cost = 0.0;                       // sum_k |r_k|^2
};

/// Simulates u (N inputs) from x0 and linearises dynamics and residuals at every stage.
OcpLinearization LinearizeAlong(const Ocp& ocp, const StateVector& x0,
                                const std::vector<InputVector>& u);

/// LinearizeAlong into `lin`, reusing its vectors (no heap allocation once they have N + 1).
void LinearizeAlong(const Ocp& ocp, const StateVector& x0, const std::vector<InputVector>& u,
                    OcpLinearization* lin);

/// Cost and its exact gradient d cost / d u (4N, stage-major) by the adjoint of the
/// single-shooting chain, from LinearizeAlong.
double OcpCostAndGradient(const Ocp& ocp, const StateVector& x0, const std::vector<InputVector>& u,
                          Eigen::VectorXd* gradient);

}  // namespace hpa
