#include "hpa/controller/ocp.h"

#include <cmath>
#include <limits>
#include <unsupported/Eigen/AutoDiff>

namespace hpa {
namespace {

using I = StateIndex;
constexpr int kRowInput = kNx;          // 4 rows: input
constexpr int kRowCam = kNx + kNu;      // 2 rows: camera x, y
constexpr double kCamMinDepthM = 0.12;  // slack L_cam off nearer the lens plane (thrown payload)
constexpr int kRowTilt = kRowCam + 2;   // 1 row: soft tilt
constexpr int kRowRate = kRowTilt + 1;  // 3 rows: soft body rate

// Rotation matrix of a (unit) quaternion w, x, y, z, for any scalar type.
template <typename T>
Eigen::Matrix<T, 3, 3> RotationOf(const T& w, const T& x, const T& y, const T& z) {
  Eigen::Matrix<T, 3, 3> r;
  r << T(1) - T(2) * (y * y + z * z), T(2) * (x * y - w * z), T(2) * (x * z + w * y),
      T(2) * (x * y + w * z), T(1) - T(2) * (x * x + z * z), T(2) * (y * z - w * x),
      T(2) * (x * z - w * y), T(2) * (y * z + w * x), T(1) - T(2) * (x * x + y * y);
  return r;
}

// p_C for any scalar type in the quaternion (the positions enter linearly).
template <typename T>
Eigen::Matrix<T, 3, 1> CameraPoint(const Ocp& ocp, const Eigen::Vector3d& d_W,
                                   const Eigen::Matrix<T, 4, 1>& q) {
  const Eigen::Matrix<T, 3, 3> r = RotationOf<T>(q(0), q(1), q(2), q(3));
  const Eigen::Matrix<T, 3, 1> d_B = r.transpose() * d_W.cast<T>();
  return ocp.R_BC.transpose().cast<T>() * (d_B - ocp.t_BC_B_m.cast<T>());
}

// Collective thrust direction and magnitude the reference point needs in `mode`:
// taut: m (a_Q + g e3) + m_L (a_L + g e3) (quadrotor plus the cable tension), slack: m (a_Q + g
// e3).
Eigen::Vector3d ThrustVector(const Params& params, const ReferencePoint& point, CableMode mode) {
  const Eigen::Vector3d g_e3(0, 0, params.gravity_mps2);
  Eigen::Vector3d f = params.quad_mass_kg * (point.a_WQ_W + g_e3);
  if (mode == CableMode::kTaut) f += params.payload_mass_kg * (point.a_WL_W + g_e3);
  return f;
}

}  // namespace

// Tuned weights. Cost units: position errors in m, velocities in m/s, quaternion components,
// rates in rad/s, inputs normalised by the hover speed. Chosen by closed-loop runs on the
// analytic plant (controller_test): hover from a 0.3 m offset settles without overshoot past
// 0.1 m, the Lissajous (a = 2, b = 0.5, T = 5 s) is tracked within the paper's RMSE scale, and
// the slack test does not dive toward the payload.
OcpWeights OcpWeights::Tuned() {
  OcpWeights w;
  // L_load: payload position/velocity strongly, quadrotor states weakly
  w.q_load << 200, 200, 200,  // payload position, 1/m^2
      15, 15, 15,             // payload velocity, (m/s)^-2
      2, 2, 2,                // quadrotor position (weak)
      1, 1, 1,                // quadrotor velocity (weak)
      0.0, 20, 20, 20,        // attitude q - q_ref (w, x, y, z); w follows from x, y, z
      0.5, 0.5, 0.5;          // body rate regularisation, (rad/s)^-2
  // L_quad: quadrotor position/velocity, payload states zero
  w.q_quad << 0, 0, 0, 0, 0, 0,            // payload: zero (free fall cannot be controlled)
      200, 200, 200,                       // quadrotor position
      15, 15, 15,                          // quadrotor velocity
      0.0, 20, 20, 20,                     // attitude
      0.5, 0.5, 0.5;                       // body rate
  w.r_input = InputVector::Constant(5.0);  // on (u - u_ref) / u_hover
  // L_cam (x perception_weight). Taut: the payload hangs at the cable's end along the thrust,
  // so it stays near the image centre; a small weight (20) keeps the Lissajous tracking (700
  // in taut mode raised the T = 3.5 s payload RMSE in y from 0.011 to 0.041 m).
  // Slack: a dead zone (cam_slack_deadzone_fraction 0.5 of the half field of view, sized from
  // the payload's current depth, off when the payload is within 0.12 m of the lens plane)
  // with a weight that beats the quadrotor position weight (200). A plain quadratic made the
  // quadrotor chase every thrown payload's predicted free fall (line_impulse with a 0.05 N s
  // sideways component: 0.43 m deviation); the dead zone follows a payload moved out of view
  // and leaves one well inside the image alone. Measured (analytic camera, `hpa run
  // scenarios/person_moves_payload.yaml --set controller.perception_weight=W`): payload in
  // view 0.65 (W = 0), 1.0 (W = 1), 1.0 (W = 10), 0.998 (W = 50), no crash up to W = 1000;
  // line_impulse with impulses [0.05,0.05,0.35], [0.2,0,0.5], [0,0.1,0.4] N s: quadrotor
  // deviation 0.23 / 0.14 / 0.20 m (nonhybrid_mpc 0.21 / 0.13 / 0.29 m).
  // L_cam uses the camera at the stage's REFERENCE attitude (cam_at_reference_attitude): the
  // paper's form with the state's attitude lets the solver cut L_cam by tilting toward the
  // payload, which at these weights tipped the quadrotor over (tilt > 90 deg at weight >= 10
  // with Q_cam 500); with the reference attitude L_cam is a cost on x_L - x_Q only, and in
  // taut flight the reference attitude is the thrust direction the cable hangs along, so it
  // keeps the paper's meaning there.
  w.q_cam_per_m2 = Eigen::Vector2d(20.0, 20.0);
  w.q_cam_slack_per_m2 = Eigen::Vector2d(1500.0, 1500.0);
  w.cam_slack_deadzone_fraction = 0.5;
  w.terminal_factor = 5.0;
  w.tilt_max_rad = 45.0 * M_PI / 180.0;
  w.tilt_weight = 1e4;
  w.body_rate_max_radps = 6.0;
  w.body_rate_weight = 10.0;
  return w;
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
  const double fraction = ocp->weights.cam_slack_deadzone_fraction;
  const Eigen::Matrix3d R_WB = state.q_WB.toRotationMatrix();
  const double depth_m =
      ((R_WB * ocp->R_BC).transpose() * (state.p_WL_W - state.p_WQ_W - R_WB * ocp->t_BC_B_m)).z();
  if (depth_m < kCamMinDepthM) {
    ocp->cam_slack_deadzone_m.setConstant(std::numeric_limits<double>::infinity());
  } else {
    ocp->cam_slack_deadzone_m = fraction * depth_m * ocp->camera_tan_half_fov;
  }
}

Ocp BuildOcp(const Params& params, const Reference& reference, double t0_s, CableMode mode,
             double perception_weight, const OcpWeights& weights) {
  Ocp ocp;
  ocp.mode = mode;
  ocp.perception_weight = perception_weight;
  ocp.weights = weights;
  ocp.u_hover_radps = params.HoverMotorSpeedRadps();
  ocp.u_min_radps = InputVector::Constant(params.motor_speed_min_radps);
  ocp.u_max_radps = InputVector::Constant(params.motor_speed_max_radps);
  ocp.R_BC = params.R_BC;
  ocp.t_BC_B_m = params.t_BC_B_m;
  ocp.camera_tan_half_fov =
      Eigen::Vector2d(0.5 * params.camera_width_px, 0.5 * params.camera_height_px) /
      params.CameraFocalPx();
  ocp.x_ref.resize(ocp.horizon_steps + 1);
  ocp.u_ref.resize(ocp.horizon_steps);
  for (int k = 0; k <= ocp.horizon_steps; ++k) {
    const ReferencePoint point = reference.At(t0_s + k * ocp.stage_dt_s);
    ocp.x_ref[k] = StateReference(params, point, mode);
    if (k < ocp.horizon_steps) ocp.u_ref[k] = InputReference(params, point, mode);
  }
  return ocp;
}

Eigen::Vector3d PayloadInCamera(const Ocp& ocp, const StateVector& x) {
  const Eigen::Vector3d d_W = x.segment<3>(I::kPayloadPos) - x.segment<3>(I::kQuadPos);
  const Eigen::Vector4d q = x.segment<4>(I::kQuat);
  return CameraPoint<double>(ocp, d_W, q);
}

Eigen::Vector3d CostPayloadInCamera(const Ocp& ocp, int k, const StateVector& x) {
  if (!ocp.weights.cam_at_reference_attitude) return PayloadInCamera(ocp, x);
  StateVector x_cam = x;
  x_cam.segment<4>(I::kQuat) =
      ocp.x_ref[std::min<int>(k, ocp.x_ref.size() - 1)].segment<4>(I::kQuat);
  return PayloadInCamera(ocp, x_cam);
}

void StageResidual(const Ocp& ocp, int k, const StateVector& x, const InputVector& u,
                   ResidualVector* r, ResidualStateJacobian* r_x, ResidualInputJacobian* r_u) {
  const bool terminal = (k >= ocp.horizon_steps);
  const OcpWeights& w = ocp.weights;
  const double state_scale = terminal ? w.terminal_factor : 1.0;
  r->setZero();
  if (r_x != nullptr) r_x->setZero();
  if (r_u != nullptr) r_u->setZero();

  // state tracking: m L_load + (1 - m) L_quad (m held over the horizon, so one of the two)
  const StateVector& q_diag = (ocp.mode == CableMode::kTaut) ? w.q_load : w.q_quad;
  StateVector x_ref = ocp.x_ref[std::min<int>(k, ocp.x_ref.size() - 1)];
  if (x.segment<4>(I::kQuat).dot(x_ref.segment<4>(I::kQuat)) < 0.0) {
    x_ref.segment<4>(I::kQuat) *= -1.0;  // same rotation, nearest sign
  }
  const StateVector sqrt_q = (state_scale * q_diag).cwiseSqrt();
  r->head<kNx>() = sqrt_q.cwiseProduct(x - x_ref);
  if (r_x != nullptr) r_x->topLeftCorner<kNx, kNx>().diagonal() = sqrt_q;

  // input cost on (u - u_ref) / u_hover
  if (!terminal) {
    const InputVector sqrt_r = w.r_input.cwiseSqrt() / ocp.u_hover_radps;
    r->segment<kNu>(kRowInput) = sqrt_r.cwiseProduct(u - ocp.u_ref[k]);
    if (r_u != nullptr) r_u->block<kNu, kNu>(kRowInput, 0).diagonal() = sqrt_r;
  }

  // perception cost on the x, y of p_C (terminal: scaled like the state cost)
  const Eigen::Vector2d& q_cam =
      (ocp.mode == CableMode::kTaut) ? w.q_cam_per_m2 : w.q_cam_slack_per_m2;
  const Eigen::Vector2d sqrt_cam = (state_scale * ocp.perception_weight * q_cam).cwiseSqrt();
  if (ocp.perception_weight > 0.0 && w.cam_at_reference_attitude) {
    // camera at the reference attitude: p_C is affine in x_L - x_Q, no attitude lever
    const StateVector& x_ref_k = ocp.x_ref[std::min<int>(k, ocp.x_ref.size() - 1)];
    const Eigen::Vector4d q_ref = x_ref_k.segment<4>(I::kQuat);
    const Eigen::Matrix3d r_ref = RotationOf<double>(q_ref(0), q_ref(1), q_ref(2), q_ref(3));
    const Eigen::Matrix3d rr = (r_ref * ocp.R_BC).transpose();
    const Eigen::Vector3d d_W = x.segment<3>(I::kPayloadPos) - x.segment<3>(I::kQuadPos);
    const Eigen::Vector3d p_C = rr * (d_W - r_ref * ocp.t_BC_B_m);
    const double deadzone = ocp.mode == CableMode::kSlack ? w.cam_slack_deadzone_fraction : 0.0;
    if (deadzone <= 0.0) {
      for (int i = 0; i < 2; ++i) {
        (*r)(kRowCam + i) = sqrt_cam(i) * p_C(i);
        if (r_x != nullptr) {
          r_x->block<1, 3>(kRowCam + i, I::kPayloadPos) = sqrt_cam(i) * rr.row(i);
          r_x->block<1, 3>(kRowCam + i, I::kQuadPos) = -sqrt_cam(i) * rr.row(i);
        }
      }
    } else {
      // dead zone: r_i = sqrt(q) (p_i - sign(p_i) d_i) where |p_i| > d_i, else 0
      for (int i = 0; i < 2; ++i) {
        const double excess = std::abs(p_C(i)) - ocp.cam_slack_deadzone_m(i);
        if (!(excess > 0.0)) continue;
        const double sign = p_C(i) > 0.0 ? 1.0 : -1.0;
        (*r)(kRowCam + i) = sqrt_cam(i) * sign * excess;
        if (r_x != nullptr) {
          r_x->block<1, 3>(kRowCam + i, I::kPayloadPos) = sqrt_cam(i) * rr.row(i);
          r_x->block<1, 3>(kRowCam + i, I::kQuadPos) = -sqrt_cam(i) * rr.row(i);
        }
      }
    }
  } else if (ocp.perception_weight > 0.0) {
    // camera at the state's attitude (the paper's literal L_cam)
    const Eigen::Vector3d d_W = x.segment<3>(I::kPayloadPos) - x.segment<3>(I::kQuadPos);
    using Ad = Eigen::AutoDiffScalar<Eigen::Vector4d>;
    Eigen::Matrix<Ad, 4, 1> q_ad;
    for (int i = 0; i < 4; ++i) q_ad(i) = Ad(x(I::kQuat + i), 4, i);
    const Eigen::Matrix<Ad, 3, 1> p_C = CameraPoint<Ad>(ocp, d_W, q_ad);
    // d p_C / d x_L = (R R_BC)^T, d p_C / d x_Q = -(R R_BC)^T
    const Eigen::Vector4d q = x.segment<4>(I::kQuat);
    const Eigen::Matrix3d rr = (RotationOf<double>(q(0), q(1), q(2), q(3)) * ocp.R_BC).transpose();
    for (int i = 0; i < 2; ++i) {
      (*r)(kRowCam + i) = sqrt_cam(i) * p_C(i).value();
      if (r_x != nullptr) {
        r_x->block<1, 3>(kRowCam + i, I::kPayloadPos) = sqrt_cam(i) * rr.row(i);
        r_x->block<1, 3>(kRowCam + i, I::kQuadPos) = -sqrt_cam(i) * rr.row(i);
        r_x->block<1, 4>(kRowCam + i, I::kQuat) = sqrt_cam(i) * p_C(i).derivatives().transpose();
      }
    }
  }

  // soft tilt limit: h = (1 - cos tilt) - (1 - cos tilt_max), 1 - cos tilt = 2 (q_x^2 + q_y^2)
  const double qx = x(I::kQuat + 1), qy = x(I::kQuat + 2);
  const double h_tilt = 2.0 * (qx * qx + qy * qy) - (1.0 - std::cos(w.tilt_max_rad));
  if (h_tilt > 0.0) {
    const double s = std::sqrt(w.tilt_weight);
    (*r)(kRowTilt) = s * h_tilt;
    if (r_x != nullptr) {
      (*r_x)(kRowTilt, I::kQuat + 1) = s * 4.0 * qx;
      (*r_x)(kRowTilt, I::kQuat + 2) = s * 4.0 * qy;
    }
  }

  // soft body-rate limit, per axis
  const double s_rate = std::sqrt(w.body_rate_weight);
  for (int i = 0; i < 3; ++i) {
    const double rate = x(I::kBodyRate + i);
    const double excess = std::abs(rate) - w.body_rate_max_radps;
    if (excess > 0.0) {
      (*r)(kRowRate + i) = s_rate * excess;
      if (r_x != nullptr) (*r_x)(kRowRate + i, I::kBodyRate + i) = s_rate * (rate > 0 ? 1 : -1);
    }
  }
}

double OcpCost(const Ocp& ocp, const HybridModel& model, const StateVector& x0,
               const std::vector<InputVector>& u, std::vector<StateVector>* x_traj) {
  const int n = ocp.horizon_steps;
  StateVector x = x0;
  double cost = 0.0;
  ResidualVector r;
  if (x_traj != nullptr) x_traj->assign(n + 1, x0);
  for (int k = 0; k < n; ++k) {
    StageResidual(ocp, k, x, u[k], &r, nullptr, nullptr);
    cost += r.squaredNorm();
    x = model.Step(x, u[k], ocp.mode, ocp.stage_dt_s);
    if (x_traj != nullptr) (*x_traj)[k + 1] = x;
  }
  StageResidual(ocp, n, x, InputVector::Zero(), &r, nullptr, nullptr);
  return cost + r.squaredNorm();
}

double OcpCostAndGradient(const Ocp& ocp, const HybridModel& model, const StateVector& x0,
                          const std::vector<InputVector>& u, Eigen::VectorXd* gradient) {
  const int n = ocp.horizon_steps;
  std::vector<StateVector> x(n + 1);
  std::vector<StateMatrix> a(n);
  std::vector<InputMatrix> b(n);
  std::vector<StateVector> gx(n + 1);
  std::vector<InputVector> gu(n);
  ResidualVector r;
  ResidualStateJacobian r_x;
  ResidualInputJacobian r_u;
  double cost = 0.0;
  x[0] = x0;
  // forward: trajectory, sensitivities, stage gradients 2 J^T r
  for (int k = 0; k < n; ++k) {
    StageResidual(ocp, k, x[k], u[k], &r, &r_x, &r_u);
    cost += r.squaredNorm();
    gx[k] = 2.0 * r_x.transpose() * r;
    gu[k] = 2.0 * r_u.transpose() * r;
    model.StepJacobians(x[k], u[k], ocp.mode, ocp.stage_dt_s, &x[k + 1], &a[k], &b[k]);
  }
  StageResidual(ocp, n, x[n], InputVector::Zero(), &r, &r_x, nullptr);
  cost += r.squaredNorm();
  // backward adjoint: lambda_N = gx_N, lambda_k = gx_k + A_k^T lambda_{k+1}
  gradient->resize(kNu * n);
  StateVector lambda = 2.0 * r_x.transpose() * r;
  for (int k = n - 1; k >= 0; --k) {
    gradient->segment<kNu>(kNu * k) = gu[k] + b[k].transpose() * lambda;
    lambda = gx[k] + a[k].transpose() * lambda;
  }
  return cost;
}

}  // namespace hpa
