#include "hpa/controller/ocp.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "exact_derivatives.h"
#include "ocp_internal.h"

namespace hpa {
namespace ocp_internal {

// The payload's offset from the quadrotor d = x_L - x_Q as L_cam sees it at stage k. In a slack
// stage the model's free fall cannot take the payload beyond the cable's length l:
// - a payload in free flight predicted outside the cable's sphere is seen on it, in the
//   direction of its predicted offset (x_Q + l d / |d|, where the cable stops and swings it).
//   Without this the free fall puts a thrown payload metres below and beside the vehicle after a
//   second, and L_cam rolls the vehicle toward that point.
// - a supported payload (ocp.payload_supported: held by a hand or a gripper) does not fall: the
//   model's fall 1/2 g t_k^2 is taken back, and a payload then outside the sphere keeps its
//   horizontal offset h with its depth bounded by the sphere, (h, sign(d_z) sqrt(l^2 - |h|^2)),
//   or l h / |h| at the equator when |h| >= l (continuous with it). Projected on the sphere
//   instead, a payload held beside the vehicle would be seen swinging under it, and L_cam would
//   never follow it.
// When d_d is not null it receives d(seen) / d(d) (3 x 3).
Eigen::Vector3d SeenPayloadOffset(const Ocp& ocp, int k, const Eigen::Vector3d& d_W,
                                  Eigen::Matrix3d* d_d) {
  const double l = ocp.model->params().cable_length_m;
  if (ocp.StageMode(k) != CableMode::kSlack) {
    if (d_d != nullptr) d_d->setIdentity();
    return d_W;
  }
  if (!ocp.payload_supported) {
    const double n = d_W.norm();
    if (!(n > l)) {
      if (d_d != nullptr) d_d->setIdentity();
      return d_W;
    }
    const Eigen::Vector3d e = d_W / n;
    if (d_d != nullptr) *d_d = (l / n) * (Eigen::Matrix3d::Identity() - e * e.transpose());
    return l * e;
  }
  const double t_k_s = k * ocp.stage_dt_s;
  const Eigen::Vector3d held_W =
      d_W + Eigen::Vector3d(0, 0, 0.5 * ocp.model->params().gravity_mps2 * t_k_s * t_k_s);
  if (!(held_W.norm() > l)) {
    if (d_d != nullptr) d_d->setIdentity();
    return held_W;
  }
  const Eigen::Vector2d h = held_W.head<2>();
  const double h_norm = h.norm();
  if (d_d != nullptr) d_d->setZero();
  if (h_norm >= l) {
    // d(l h / |h|) / dh = (l / |h|) (I - e e^T)
    const Eigen::Vector2d e = h / h_norm;
    if (d_d != nullptr) {
      d_d->topLeftCorner<2, 2>() = (l / h_norm) * (Eigen::Matrix2d::Identity() - e * e.transpose());
    }
    return Eigen::Vector3d(l * e.x(), l * e.y(), 0.0);
  }
  const double sign = held_W.z() < 0.0 ? -1.0 : 1.0;
  const double depth_m = std::sqrt(l * l - h_norm * h_norm);
  if (d_d != nullptr) {
    // d z / dh = -sign h / depth, bounded near the equator where the slope grows without bound
    constexpr double kMinDepthForSlopeM = 1e-3;
    d_d->topLeftCorner<2, 2>().setIdentity();
    d_d->block<1, 2>(2, 0) = -sign * h.transpose() / std::max(depth_m, kMinDepthForSlopeM);
  }
  return Eigen::Vector3d(h.x(), h.y(), sign * depth_m);
}

Eigen::Matrix<double, 3, 4> CameraPointQuatJacobian(const Ocp& ocp, const Eigen::Vector3d& d_W,
                                                    const Eigen::Vector4d& q) {
  const double w = q(0), x = q(1), y = q(2), z = q(3);
  // d R / d q_j, R = RotationOf(w, x, y, z)
  Eigen::Matrix3d r_q[4];
  r_q[0] << 0.0, -z, y, z, 0.0, -x, -y, x, 0.0;
  r_q[1] << 0.0, y, z, y, -2.0 * x, -w, z, w, -2.0 * x;
  r_q[2] << -2.0 * y, x, w, x, 0.0, z, -w, z, -2.0 * y;
  r_q[3] << -2.0 * z, -w, x, w, -2.0 * z, y, x, y, 0.0;
  Eigen::Matrix<double, 3, 4> p_q;
  for (int j = 0; j < 4; ++j) p_q.col(j) = 2.0 * ocp.R_BC.transpose() * (r_q[j].transpose() * d_W);
  return p_q;
}

}  // namespace ocp_internal

namespace {

using I = StateIndex;
using ocp_internal::CameraPoint;
using ocp_internal::kCamMinDepthM;
using ocp_internal::SeenPayloadOffset;
using ocp_internal::StageStateReference;

// Collective thrust vector the reference point needs: taut m (a_Q + g e3) + m_L (a_L + g e3)
// (quadrotor plus the cable tension), slack m (a_Q + g e3).
Eigen::Vector3d ThrustVector(const Params& params, const ReferencePoint& point, CableMode mode) {
  const Eigen::Vector3d g_e3(0, 0, params.gravity_mps2);
  Eigen::Vector3d f = params.quad_mass_kg * (point.a_WQ_W + g_e3);
  if (mode == CableMode::kTaut) f += params.payload_mass_kg * (point.a_WL_W + g_e3);
  return f;
}

}  // namespace

// Tuned weights (why each has its value: controller/README.md, "Tuning history"). Units:
// position errors in m, velocities in m/s, quaternion components, rates in rad/s, inputs
// normalised by the hover speed.
OcpWeights OcpWeights::Tuned() {
  OcpWeights w;
  // L_load (taut): payload position/velocity strongly, quadrotor states weakly
  w.q_load << 200, 200, 200,  // payload position, 1/m^2
      15, 15, 15,             // payload velocity, (m/s)^-2
      2, 2, 2,                // quadrotor position (weak)
      1, 1, 1,                // quadrotor velocity (weak)
      0.0, 20, 20, 20,        // attitude q - q_ref (w, x, y, z); w follows from x, y, z
      0.5, 0.5, 0.5;          // body rate regularisation, (rad/s)^-2
  // L_quad (slack): quadrotor position/velocity, payload zero (its free fall is not controllable)
  w.q_quad << 0, 0, 0, 0, 0, 0,            // payload
      200, 200, 200,                       // quadrotor position
      15, 15, 15,                          // quadrotor velocity
      0.0, 20, 20, 20,                     // attitude
      0.5, 0.5, 0.5;                       // body rate
  w.r_input = InputVector::Constant(5.0);  // on (u - u_ref) / u_hover
  // L_cam (x perception_weight): small in taut mode, beats the quadrotor position in slack
  w.q_cam_per_m2 = Eigen::Vector2d(20.0, 20.0);
  w.q_cam_slack_per_m2 = Eigen::Vector2d(1500.0, 1500.0);
  w.cam_slack_deadzone_fraction = 0.5;
  w.cam_held_deadzone_fraction = 0.15;
  w.terminal_factor = 5.0;
  w.tilt_max_rad = 45.0 * M_PI / 180.0;
  w.tilt_weight = 1e4;
  w.body_rate_max_radps = 6.0;
  w.body_rate_weight = 10.0;
  return w;
}

StateVector Ocp::Step(int k, const StateVector& x, const InputVector& u) const {
  const StateVector x_next = model->Step(x, u, StageMode(k), stage_dt_s);
  return k + 1 == retaut_stage ? model->ProjectToTaut(x_next) : x_next;
}

void Ocp::StepJacobians(int k, const StateVector& x, const InputVector& u, StateVector* x_next,
                        StateMatrix* a, InputMatrix* b) const {
  ExactStepJacobians(*model, x, u, StageMode(k), stage_dt_s, x_next, a, b);
  if (k + 1 != retaut_stage) return;
  // chain rule through the jump map: d y / d x = J (d F / d x), d y / d u = J (d F / d u)
  StateMatrix jump;
  *x_next = ExactJumpJacobian(*model, *x_next, &jump);
  *a = (jump * *a).eval();
  *b = (jump * *b).eval();
}

StateVector StateReference(const Params& params, const ReferencePoint& point, CableMode mode) {
  // attitude: body z along the needed thrust, yaw 0 (shortest rotation from e3)
  const Eigen::Vector3d z_B = ThrustVector(params, point, mode).normalized();
  const Eigen::Quaterniond q_WB = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), z_B);
  StateVector x;
  x << point.p_WL_W, point.v_WL_W, point.p_WQ_W, point.v_WQ_W, q_WB.w(), q_WB.x(), q_WB.y(),
      q_WB.z(), Eigen::Vector3d::Zero();
  return x;
}

InputVector InputReference(const Params& params, const ReferencePoint& point, CableMode mode) {
  const double thrust_N = ThrustVector(params, point, mode).norm();
  return InputVector::Constant(std::sqrt(thrust_N / (4.0 * params.k_f_N_per_radps2)));
}

void SetCameraDeadzone(const SystemState& state, Ocp* ocp) {
  const double fraction = ocp_internal::SlackDeadzoneFraction(*ocp);
  const Eigen::Matrix3d R_WB = state.q_WB.toRotationMatrix();
  const double depth_m =
      ((R_WB * ocp->R_BC).transpose() * (state.p_WL_W - state.p_WQ_W - R_WB * ocp->t_BC_B_m)).z();
  if (depth_m < kCamMinDepthM) {
    ocp->cam_slack_deadzone_m.setConstant(std::numeric_limits<double>::infinity());
  } else {
    ocp->cam_slack_deadzone_m = fraction * depth_m * ocp->camera_tan_half_fov;
  }
}

void SetCameraDeadzonesAlong(const StateVector& x0, const std::vector<InputVector>& u, Ocp* ocp) {
  ocp->cam_slack_deadzone_stage_m.clear();
  if (ocp->mode != CableMode::kSlack) return;
  const int n = ocp->horizon_steps;
  const double fraction = ocp->weights.cam_slack_deadzone_fraction;
  const Eigen::Vector2d off = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  ocp->cam_slack_deadzone_stage_m.assign(n + 1, off);
  ocp->cam_slack_deadzone_stage_m[0] = ocp->cam_slack_deadzone_m;
  // a supported payload stays at the depth it is held at: every stage keeps stage 0's dead zone
  if (ocp->payload_supported) {
    ocp->cam_slack_deadzone_stage_m.assign(n + 1, ocp->cam_slack_deadzone_m);
    return;
  }
  StateVector x = x0;
  for (int k = 0; k < n && k < static_cast<int>(u.size()); ++k) {
    x = ocp->Step(k, x, u[k]);
    if (ocp->StageMode(k + 1) != CableMode::kSlack) continue;  // a scheduled re-taut
    const double depth_m = CostPayloadInCamera(*ocp, k + 1, x).z();
    if (depth_m < kCamMinDepthM) {
      // a free payload predicted to come up to the lens plane: L_cam off over the whole horizon
      ocp->cam_slack_deadzone_stage_m.assign(n + 1, off);
      return;
    }
    ocp->cam_slack_deadzone_stage_m[k + 1] = fraction * depth_m * ocp->camera_tan_half_fov;
  }
}

int PredictRetautStage(const Ocp& ocp, const StateVector& x0, const std::vector<InputVector>& u) {
  if (ocp.mode != CableMode::kSlack) return -1;
  const double l = ocp.model->params().cable_length_m;
  StateVector x = x0;
  for (int k = 0; k < ocp.horizon_steps && k < static_cast<int>(u.size()); ++k) {
    x = ocp.model->Step(x, u[k], CableMode::kSlack, ocp.stage_dt_s);
    const Eigen::Vector3d r = x.segment<3>(I::kPayloadPos) - x.segment<3>(I::kQuadPos);
    const Eigen::Vector3d v_rel = x.segment<3>(I::kPayloadVel) - x.segment<3>(I::kQuadVel);
    if (r.norm() >= l && v_rel.dot(r) > 0.0) return k + 1;
  }
  return -1;
}

void ScheduleRetaut(const Reference& reference, double t0_s, int stage, Ocp* ocp) {
  const int previous = ocp->retaut_stage;
  ocp->retaut_stage = stage >= 1 && stage <= ocp->horizon_steps ? stage : -1;
  // only the stages the old or the new schedule makes taut change their references
  int first = ocp->horizon_steps + 1;
  if (previous >= 1) first = std::min(first, previous);
  if (ocp->retaut_stage >= 1) first = std::min(first, ocp->retaut_stage);
  const Params& params = ocp->model->params();
  for (int k = first; k <= ocp->horizon_steps; ++k) {
    const ReferencePoint point = reference.At(t0_s + k * ocp->stage_dt_s);
    ocp->x_ref[k] = StateReference(params, point, ocp->StageMode(k));
    if (k < ocp->horizon_steps) ocp->u_ref[k] = InputReference(params, point, ocp->StageMode(k));
  }
}

Ocp BuildOcp(std::shared_ptr<const HybridModel> model, const Reference& reference, double t0_s,
             CableMode mode, double perception_weight, const OcpWeights& weights) {
  Ocp ocp;
  BuildOcp(std::move(model), reference, t0_s, mode, perception_weight, weights, &ocp);
  return ocp;
}

void BuildOcp(std::shared_ptr<const HybridModel> model, const Reference& reference, double t0_s,
              CableMode mode, double perception_weight, const OcpWeights& weights, Ocp* ocp) {
  const Params& params = model->params();
  // a fresh problem that keeps the vectors' memory
  std::vector<StateVector> x_ref = std::move(ocp->x_ref);
  std::vector<InputVector> u_ref = std::move(ocp->u_ref);
  std::vector<Eigen::Vector2d> deadzones = std::move(ocp->cam_slack_deadzone_stage_m);
  *ocp = Ocp();
  ocp->x_ref = std::move(x_ref);
  ocp->u_ref = std::move(u_ref);
  ocp->cam_slack_deadzone_stage_m = std::move(deadzones);
  ocp->cam_slack_deadzone_stage_m.clear();
  ocp->mode = mode;
  ocp->perception_weight = perception_weight;
  ocp->weights = weights;
  ocp->u_hover_radps = params.HoverMotorSpeedRadps();
  ocp->u_min_radps = InputVector::Constant(params.motor_speed_min_radps);
  ocp->u_max_radps = InputVector::Constant(params.motor_speed_max_radps);
  ocp->R_BC = params.R_BC;
  ocp->t_BC_B_m = params.t_BC_B_m;
  ocp->camera_tan_half_fov =
      Eigen::Vector2d(0.5 * params.camera_width_px, 0.5 * params.camera_height_px) /
      params.CameraFocalPx();
  ocp->x_ref.resize(ocp->horizon_steps + 1);
  ocp->u_ref.resize(ocp->horizon_steps);
  for (int k = 0; k <= ocp->horizon_steps; ++k) {
    const ReferencePoint point = reference.At(t0_s + k * ocp->stage_dt_s);
    ocp->x_ref[k] = StateReference(params, point, mode);
    if (k < ocp->horizon_steps) ocp->u_ref[k] = InputReference(params, point, mode);
  }
  ocp->model = std::move(model);
}

Ocp BuildOcp(const Params& params, const Reference& reference, double t0_s, CableMode mode,
             double perception_weight, const OcpWeights& weights) {
  return BuildOcp(std::make_shared<const HybridModel>(params), reference, t0_s, mode,
                  perception_weight, weights);
}

Eigen::Vector3d PayloadInCamera(const Ocp& ocp, const StateVector& x) {
  const Eigen::Vector3d d_W = x.segment<3>(I::kPayloadPos) - x.segment<3>(I::kQuadPos);
  const Eigen::Vector4d q = x.segment<4>(I::kQuat);
  return CameraPoint<double>(ocp, d_W, q);
}

Eigen::Vector3d CostPayloadInCamera(const Ocp& ocp, int k, const StateVector& x) {
  StateVector x_cam = x;
  x_cam.segment<3>(I::kPayloadPos) =
      x.segment<3>(I::kQuadPos) +
      SeenPayloadOffset(ocp, k, x.segment<3>(I::kPayloadPos) - x.segment<3>(I::kQuadPos), nullptr);
  if (ocp.weights.cam_at_reference_attitude) {
    x_cam.segment<4>(I::kQuat) = StageStateReference(ocp, k).segment<4>(I::kQuat);
  }
  return PayloadInCamera(ocp, x_cam);
}
double OcpCost(const Ocp& ocp, const StateVector& x0, const std::vector<InputVector>& u,
               std::vector<StateVector>* x_traj) {
  const int n = ocp.horizon_steps;
  StateVector x = x0;
  double cost = 0.0;
  ResidualVector r;
  if (x_traj != nullptr) x_traj->assign(n + 1, x0);
  for (int k = 0; k < n; ++k) {
    StageResidual(ocp, k, x, u[k], &r, nullptr, nullptr);
    cost += r.squaredNorm();
    x = ocp.Step(k, x, u[k]);
    if (x_traj != nullptr) (*x_traj)[k + 1] = x;
  }
  StageResidual(ocp, n, x, InputVector::Zero(), &r, nullptr, nullptr);
  return cost + r.squaredNorm();
}

OcpLinearization LinearizeAlong(const Ocp& ocp, const StateVector& x0,
                                const std::vector<InputVector>& u) {
  OcpLinearization lin;
  LinearizeAlong(ocp, x0, u, &lin);
  return lin;
}

void LinearizeAlong(const Ocp& ocp, const StateVector& x0, const std::vector<InputVector>& u,
                    OcpLinearization* lin) {
  const int n = ocp.horizon_steps;
  lin->x.resize(n + 1);
  lin->a.resize(n);
  lin->b.resize(n);
  lin->r.resize(n + 1);
  lin->r_x.resize(n + 1);
  lin->r_u.resize(n + 1);
  lin->x[0] = x0;
  double cost = 0.0;
  for (int k = 0; k < n; ++k) {
    StageResidual(ocp, k, lin->x[k], u[k], &lin->r[k], &lin->r_x[k], &lin->r_u[k]);
    cost += lin->r[k].squaredNorm();
    ocp.StepJacobians(k, lin->x[k], u[k], &lin->x[k + 1], &lin->a[k], &lin->b[k]);
  }
  StageResidual(ocp, n, lin->x[n], InputVector::Zero(), &lin->r[n], &lin->r_x[n], &lin->r_u[n]);
  lin->cost = cost + lin->r[n].squaredNorm();
}

double OcpCostAndGradient(const Ocp& ocp, const StateVector& x0, const std::vector<InputVector>& u,
                          Eigen::VectorXd* gradient) {
  const int n = ocp.horizon_steps;
  const OcpLinearization lin = LinearizeAlong(ocp, x0, u);
  // stage gradients 2 J^T r
  std::vector<StateVector> gx(n + 1);
  std::vector<InputVector> gu(n);
  for (int k = 0; k < n; ++k) {
    gx[k] = 2.0 * lin.r_x[k].transpose() * lin.r[k];
    gu[k] = 2.0 * lin.r_u[k].transpose() * lin.r[k];
  }
  // backward adjoint: lambda_N = gx_N, lambda_k = gx_k + A_k^T lambda_{k+1}
  gradient->resize(kNu * n);
  StateVector lambda = 2.0 * lin.r_x[n].transpose() * lin.r[n];
  for (int k = n - 1; k >= 0; --k) {
    gradient->segment<kNu>(kNu * k) = gu[k] + lin.b[k].transpose() * lambda;
    lambda = gx[k] + lin.a[k].transpose() * lambda;
  }
  return lin.cost;
}

}  // namespace hpa
