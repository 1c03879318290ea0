#pragma once
// The HPA-MPC optimal control problem as a plain struct (OCS2 habit): horizon, mode held over
// the horizon, state/input references, diagonal weights. Any solver (RTI, NLopt) takes it.
//
// Cost, written as a sum of squared residuals: J = sum_{k<N} |r_k(x_k, u_k)|^2 + |r_N(x_N)|^2,
//   |r_k|^2 = m L_load + (1 - m) L_quad + L_cam + soft tilt + soft body rate + input cost,
// with every quadratic term e^T Q e, Q diagonal. Rotor-speed bounds are hard box constraints
// of the solvers; tilt and body-rate limits are SOFT: one-sided quadratic penalties
// w max(0, h(x))^2 (they never make the problem infeasible).

#include <Eigen/Core>
#include <vector>

#include "hpa/controller/reference.h"
#include "hpa/models/hybrid_model.h"
#include "hpa/models/params.h"
#include "hpa/models/state.h"

namespace hpa {

constexpr int kOcpHorizonSteps = 10;        // N
constexpr double kOcpStageDtS = 0.1;        // s per stage: horizon 1 s
constexpr int kNr = kNx + kNu + 2 + 1 + 3;  // residual rows: state, input, camera x/y, tilt, rates

using ResidualVector = Eigen::Matrix<double, kNr, 1>;
using ResidualStateJacobian = Eigen::Matrix<double, kNr, kNx>;
using ResidualInputJacobian = Eigen::Matrix<double, kNr, kNu>;

/// Diagonal weights of the stage cost (the tuned defaults are documented in ocp.cc).
struct OcpWeights {
  StateVector q_load;            // L_load: taut mode, on x - x_ref  (19)
  StateVector q_quad;            // L_quad: slack mode, on x - x_ref; payload entries zero  (19)
  InputVector r_input;           // on (u - u_ref) / u_hover, dimensionless  (4)
  Eigen::Vector2d q_cam_per_m2;  // L_cam in taut mode, on the x, y of p_C (m)  (2)
  Eigen::Vector2d q_cam_slack_per_m2;  // L_cam in slack mode (both x perception_weight)  (2)
  // L_cam's camera attitude: true -> the stage's reference attitude (L_cam is then a cost on
  // positions only; the default, see ocp.cc), false -> the state's attitude (the paper's
  // literal form, whose attitude lever tips the quadrotor over at high perception weight).
  bool cam_at_reference_attitude = true;
  // Slack-mode L_cam penalises only the part of the payload's image offset beyond this
  // fraction of the half field of view (per axis, a dead zone): a payload moved out of view is
  // followed, a thrown one still well inside the image is not chased. 0 = the paper's plain
  // quadratic.
  double cam_slack_deadzone_fraction = 0.0;
  double terminal_factor = 1.0;      // terminal state weights = factor * stage state weights
  double tilt_max_rad = 0.0;         // soft limit on the angle between body z and world z
  double tilt_weight = 0.0;          // weight on max(0, (1 - cos tilt) - (1 - cos tilt_max))^2
  double body_rate_max_radps = 0.0;  // soft limit on each |w_B|
  double body_rate_weight = 0.0;     // weight on max(0, |w_i| - max)^2, (rad/s)^-2

  /// The tuned weights (see ocp.cc for the values and why).
  static OcpWeights Tuned();
};

/// One instance of the optimal control problem.
struct Ocp {
  int horizon_steps = kOcpHorizonSteps;  // N
  double stage_dt_s = kOcpStageDtS;      // stage length
  CableMode mode = CableMode::kTaut;     // held over the horizon
  double perception_weight = 1.0;        // scale on q_cam (0: L_cam off)
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
};

/// Sets ocp->cam_slack_deadzone_m from the current state: deadzone fraction x tan(half FOV) x
/// the payload's depth in the camera; a payload at or above the lens plane (thrown up) cannot
/// be brought into view by moving, so the slack L_cam is switched off (infinite dead zone).
void SetCameraDeadzone(const SystemState& state, Ocp* ocp);

/// Builds the OCP at time t0_s: references from `reference` at t0 + k dt, mode, weights,
/// bounds and camera transform from params.
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
/// stage k when weights.cam_at_reference_attitude (the default), else the state's.
Eigen::Vector3d CostPayloadInCamera(const Ocp& ocp, int k, const StateVector& x);

/// Residual of stage k (k = N: terminal, u ignored and its rows zero) and, if asked, its
/// Jacobians. Stage cost = r.squaredNorm().
void StageResidual(const Ocp& ocp, int k, const StateVector& x, const InputVector& u,
                   ResidualVector* r, ResidualStateJacobian* r_x, ResidualInputJacobian* r_u);

/// Simulates u from x0 with the OCP's mode and returns the cost; x_traj (N+1) if not null.
double OcpCost(const Ocp& ocp, const HybridModel& model, const StateVector& x0,
               const std::vector<InputVector>& u, std::vector<StateVector>* x_traj = nullptr);

/// Cost and its exact gradient d cost / d u (4N, stage-major) by the adjoint of the
/// single-shooting chain (exact sensitivities from HybridModel::StepJacobians).
double OcpCostAndGradient(const Ocp& ocp, const HybridModel& model, const StateVector& x0,
                          const std::vector<InputVector>& u, Eigen::VectorXd* gradient);

}  // namespace hpa
