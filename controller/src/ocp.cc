#include "hpa/controller/ocp.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <unsupported/Eigen/AutoDiff>

namespace hpa {
namespace {

using I = StateIndex;
constexpr double kCamMinDepthM = 0.12;  // slack L_cam off nearer the lens plane (thrown payload)

// The payload's offset from the quadrotor d = x_L - x_Q as L_cam sees it at stage k. In a slack
// stage the free-fall prediction cannot take the payload beyond the cable's length l: a payload
// predicted outside the cable's sphere is seen on it, in the direction of its predicted offset
// (x_Q + l d / |d|, where the cable stops and swings it). Without this the held free fall puts
// the payload metres below and beside the vehicle after a second, and L_cam chases that point.
// When d_d is not null it receives d(seen) / d(d) (3 x 3).
Eigen::Vector3d SeenPayloadOffset(const Ocp& ocp, int k, const Eigen::Vector3d& d_W,
                                  Eigen::Matrix3d* d_d) {
  const double l = ocp.model->params().cable_length_m;
  const double n = d_W.norm();
  if (ocp.StageMode(k) != CableMode::kSlack || !(n > l)) {
    if (d_d != nullptr) d_d->setIdentity();
    return d_W;
  }
  const Eigen::Vector3d e = d_W / n;
  if (d_d != nullptr) *d_d = (l / n) * (Eigen::Matrix3d::Identity() - e * e.transpose());
  return l * e;
}

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

// Collective thrust vector the reference point needs: taut m (a_Q + g e3) + m_L (a_L + g e3)
// (quadrotor plus the cable tension), slack m (a_Q + g e3).
Eigen::Vector3d ThrustVector(const Params& params, const ReferencePoint& point, CableMode mode) {
  const Eigen::Vector3d g_e3(0, 0, params.gravity_mps2);
  Eigen::Vector3d f = params.quad_mass_kg * (point.a_WQ_W + g_e3);
  if (mode == CableMode::kTaut) f += params.payload_mass_kg * (point.a_WL_W + g_e3);
  return f;
}

// State reference of stage k (the terminal one past the horizon).
const StateVector& StageStateReference(const Ocp& ocp, int k) {
  return ocp.x_ref[std::min<int>(k, ocp.x_ref.size() - 1)];
}

// --- the terms: weight per mode and weighted residual --------------------------------------

// State tracking weight of the block [kStart, kStart + kRows): Q_load taut, Q_quad slack.
template <int kStart, int kRows>
OcpTermWeight StateWeight(const OcpWeights& w, CableMode mode) {
  const StateVector& q = mode == CableMode::kTaut ? w.q_load : w.q_quad;
  return q.segment<kRows>(kStart);
}

// State tracking residual sqrt(q) (x - x_ref) of one vector block of the state.
template <int kStart, int kRows>
void StateError(const Ocp& ocp, int k, const StateVector& x, const InputVector&,
                const OcpTermWeight& sqrt_w, OcpTermResidual* r, OcpTermStateJacobian* r_x,
                OcpTermInputJacobian*) {
  const StateVector& x_ref = StageStateReference(ocp, k);
  *r = sqrt_w.cwiseProduct(x.segment<kRows>(kStart) - x_ref.segment<kRows>(kStart));
  if (r_x != nullptr) r_x->middleCols<kRows>(kStart).diagonal() = sqrt_w;
}

// Attitude residual sqrt(q) (q - q_ref), q_ref taken with the sign nearest q (same rotation).
void AttitudeError(const Ocp& ocp, int k, const StateVector& x, const InputVector&,
                   const OcpTermWeight& sqrt_w, OcpTermResidual* r, OcpTermStateJacobian* r_x,
                   OcpTermInputJacobian*) {
  Eigen::Vector4d q_ref = StageStateReference(ocp, k).segment<4>(I::kQuat);
  if (x.segment<4>(I::kQuat).dot(q_ref) < 0.0) q_ref *= -1.0;
  *r = sqrt_w.cwiseProduct(x.segment<4>(I::kQuat) - q_ref);
  if (r_x != nullptr) r_x->middleCols<4>(I::kQuat).diagonal() = sqrt_w;
}

// Input weight R (per rotor, both modes).
OcpTermWeight InputWeight(const OcpWeights& w, CableMode) { return w.r_input; }

// Input residual sqrt(R) (u - u_ref) / u_hover.
void InputError(const Ocp& ocp, int k, const StateVector&, const InputVector& u,
                const OcpTermWeight& sqrt_w, OcpTermResidual* r, OcpTermStateJacobian*,
                OcpTermInputJacobian* r_u) {
  const InputVector sqrt_r = sqrt_w / ocp.u_hover_radps;
  *r = sqrt_r.cwiseProduct(u - ocp.u_ref[k]);
  if (r_u != nullptr) r_u->diagonal() = sqrt_r;
}

// L_cam weight per mode (taut: the payload hangs in view; slack: beyond the dead zone).
OcpTermWeight PerceptionWeight(const OcpWeights& w, CableMode mode) {
  return mode == CableMode::kTaut ? w.q_cam_per_m2 : w.q_cam_slack_per_m2;
}

// L_cam is scaled by the controller's perception weight.
double PerceptionScale(const Ocp& ocp) { return ocp.perception_weight; }

// L_cam residual: sqrt(q_cam) times the x, y of p_C (slack: beyond the dead zone).
void PerceptionError(const Ocp& ocp, int k, const StateVector& x, const InputVector&,
                     const OcpTermWeight& sqrt_cam, OcpTermResidual* r, OcpTermStateJacobian* r_x,
                     OcpTermInputJacobian*) {
  const OcpWeights& w = ocp.weights;
  Eigen::Matrix3d d_d;  // d(seen offset) / d(x_L - x_Q)
  const Eigen::Vector3d d_W =
      SeenPayloadOffset(ocp, k, x.segment<3>(I::kPayloadPos) - x.segment<3>(I::kQuadPos), &d_d);
  if (w.cam_at_reference_attitude) {
    // camera at the reference attitude: p_C is affine in the seen offset, no attitude lever
    const Eigen::Vector4d q_ref = StageStateReference(ocp, k).segment<4>(I::kQuat);
    const Eigen::Matrix3d r_ref = RotationOf<double>(q_ref(0), q_ref(1), q_ref(2), q_ref(3));
    const Eigen::Matrix3d rr = (r_ref * ocp.R_BC).transpose();
    const Eigen::Vector3d p_C = rr * (d_W - r_ref * ocp.t_BC_B_m);
    const Eigen::Matrix3d p_d = rr * d_d;  // d p_C / d x_L = -d p_C / d x_Q
    const double deadzone =
        ocp.StageMode(k) == CableMode::kSlack ? w.cam_slack_deadzone_fraction : 0.0;
    for (int i = 0; i < 2; ++i) {
      const double slope = sqrt_cam(i);  // d r_i / d p_i, with or without the dead zone
      if (deadzone <= 0.0) {
        (*r)(i) = sqrt_cam(i) * p_C(i);
      } else {
        // dead zone: r_i = sqrt(q) (p_i - sign(p_i) d_i) where |p_i| > d_i, else 0
        const double excess = std::abs(p_C(i)) - ocp.CamSlackDeadzone(k)(i);
        if (!(excess > 0.0)) continue;
        const double sign = p_C(i) > 0.0 ? 1.0 : -1.0;
        (*r)(i) = sqrt_cam(i) * sign * excess;
      }
      if (r_x != nullptr) {
        r_x->block<1, 3>(i, I::kPayloadPos) = slope * p_d.row(i);
        r_x->block<1, 3>(i, I::kQuadPos) = -slope * p_d.row(i);
      }
    }
    return;
  }
  // camera at the state's attitude (the paper's literal L_cam); off where the payload is at the
  // lens plane
  if (ocp.StageMode(k) == CableMode::kSlack && !std::isfinite(ocp.CamSlackDeadzone(k)(0))) return;
  using Ad = Eigen::AutoDiffScalar<Eigen::Vector4d>;
  Eigen::Matrix<Ad, 4, 1> q_ad;
  for (int i = 0; i < 4; ++i) q_ad(i) = Ad(x(I::kQuat + i), 4, i);
  const Eigen::Matrix<Ad, 3, 1> p_C = CameraPoint<Ad>(ocp, d_W, q_ad);
  // d p_C / d x_L = (R R_BC)^T d_d, d p_C / d x_Q = -(R R_BC)^T d_d
  const Eigen::Vector4d q = x.segment<4>(I::kQuat);
  const Eigen::Matrix3d rr = (RotationOf<double>(q(0), q(1), q(2), q(3)) * ocp.R_BC).transpose();
  const Eigen::Matrix3d p_d = rr * d_d;
  for (int i = 0; i < 2; ++i) {
    (*r)(i) = sqrt_cam(i) * p_C(i).value();
    if (r_x != nullptr) {
      r_x->block<1, 3>(i, I::kPayloadPos) = sqrt_cam(i) * p_d.row(i);
      r_x->block<1, 3>(i, I::kQuadPos) = -sqrt_cam(i) * p_d.row(i);
      r_x->block<1, 4>(i, I::kQuat) = sqrt_cam(i) * p_C(i).derivatives().transpose();
    }
  }
}

// Soft tilt weight (both modes).
OcpTermWeight TiltWeight(const OcpWeights& w, CableMode) {
  return OcpTermWeight::Constant(1, w.tilt_weight);
}

// Soft tilt: sqrt(w) h where h = (1 - cos tilt) - (1 - cos tilt_max) > 0, 1 - cos = 2 (qx^2+qy^2).
void TiltExcess(const Ocp& ocp, int, const StateVector& x, const InputVector&,
                const OcpTermWeight& sqrt_w, OcpTermResidual* r, OcpTermStateJacobian* r_x,
                OcpTermInputJacobian*) {
  const double qx = x(I::kQuat + 1), qy = x(I::kQuat + 2);
  const double h_tilt = 2.0 * (qx * qx + qy * qy) - (1.0 - std::cos(ocp.weights.tilt_max_rad));
  if (!(h_tilt > 0.0)) return;
  const double s = sqrt_w(0);
  (*r)(0) = s * h_tilt;
  if (r_x != nullptr) {
    (*r_x)(0, I::kQuat + 1) = s * 4.0 * qx;
    (*r_x)(0, I::kQuat + 2) = s * 4.0 * qy;
  }
}

// Soft body-rate weight (per axis, both modes).
OcpTermWeight BodyRateLimitWeight(const OcpWeights& w, CableMode) {
  return OcpTermWeight::Constant(3, w.body_rate_weight);
}

// Soft body-rate limit: sqrt(w) (|w_i| - max) where positive, per axis.
void BodyRateExcess(const Ocp& ocp, int, const StateVector& x, const InputVector&,
                    const OcpTermWeight& sqrt_w, OcpTermResidual* r, OcpTermStateJacobian* r_x,
                    OcpTermInputJacobian*) {
  for (int i = 0; i < 3; ++i) {
    const double rate = x(I::kBodyRate + i);
    const double excess = std::abs(rate) - ocp.weights.body_rate_max_radps;
    if (excess > 0.0) {
      (*r)(i) = sqrt_w(i) * excess;
      if (r_x != nullptr) (*r_x)(i, I::kBodyRate + i) = sqrt_w(i) * (rate > 0 ? 1 : -1);
    }
  }
}

// The term list with each term's first row: offsets follow from the order, never written.
template <size_t kCount>
constexpr std::array<OcpTerm, kCount> WithOffsets(const OcpTerm (&terms)[kCount]) {
  std::array<OcpTerm, kCount> out{};
  int offset = 0;
  for (size_t i = 0; i < kCount; ++i) {
    out[i] = terms[i];
    out[i].offset = offset;
    offset += terms[i].rows;
  }
  return out;
}

// The stage cost: one line per term (name, rows, terminal role, weight, scale, residual).
// m L_load + (1 - m) L_quad is the six state-tracking terms with their per-mode weights.
constexpr OcpTermAtTerminal kTerminalFactor = OcpTermAtTerminal::kTimesTerminalFactor;
constexpr OcpTerm kTermList[] = {
    {"payload_position", 3, kTerminalFactor, &StateWeight<I::kPayloadPos, 3>, nullptr,
     &StateError<I::kPayloadPos, 3>},
    {"payload_velocity", 3, kTerminalFactor, &StateWeight<I::kPayloadVel, 3>, nullptr,
     &StateError<I::kPayloadVel, 3>},
    {"quad_position", 3, kTerminalFactor, &StateWeight<I::kQuadPos, 3>, nullptr,
     &StateError<I::kQuadPos, 3>},
    {"quad_velocity", 3, kTerminalFactor, &StateWeight<I::kQuadVel, 3>, nullptr,
     &StateError<I::kQuadVel, 3>},
    {"attitude", 4, kTerminalFactor, &StateWeight<I::kQuat, 4>, nullptr, &AttitudeError},
    {"body_rate", 3, kTerminalFactor, &StateWeight<I::kBodyRate, 3>, nullptr,
     &StateError<I::kBodyRate, 3>},
    {"input", kNu, OcpTermAtTerminal::kOmitted, &InputWeight, nullptr, &InputError},
    {"perception", 2, kTerminalFactor, &PerceptionWeight, &PerceptionScale, &PerceptionError},
    {"tilt_limit", 1, OcpTermAtTerminal::kAsStage, &TiltWeight, nullptr, &TiltExcess},
    {"body_rate_limit", 3, OcpTermAtTerminal::kAsStage, &BodyRateLimitWeight, nullptr,
     &BodyRateExcess},
};
constexpr auto kTerms = WithOffsets(kTermList);
static_assert(kTerms.back().offset + kTerms.back().rows == kNr,
              "kNr (ocp.h) must be the sum of the term rows");

// Evaluates one term into its rows of the full residual and Jacobians (already zeroed).
void EvaluateTerm(const Ocp& ocp, const OcpTerm& term, int k, const StateVector& x,
                  const InputVector& u, ResidualVector* r, ResidualStateJacobian* r_x,
                  ResidualInputJacobian* r_u) {
  const OcpTermWeight weight = OcpTermStageWeight(ocp, term, k);
  if (!(weight.array() > 0.0).any()) return;
  const OcpTermWeight sqrt_weight = weight.cwiseSqrt();
  OcpTermResidual r_rows(*r, term.offset, 0, term.rows, 1);
  if (r_x == nullptr && r_u == nullptr) {
    term.residual(ocp, k, x, u, sqrt_weight, &r_rows, nullptr, nullptr);
    return;
  }
  // a block needs a matrix to view: an unrequested Jacobian views scratch that is never written
  ResidualStateJacobian r_x_unused;
  ResidualInputJacobian r_u_unused;
  OcpTermStateJacobian r_x_rows(r_x != nullptr ? *r_x : r_x_unused, term.offset, 0, term.rows, kNx);
  OcpTermInputJacobian r_u_rows(r_u != nullptr ? *r_u : r_u_unused, term.offset, 0, term.rows, kNu);
  term.residual(ocp, k, x, u, sqrt_weight, &r_rows, r_x != nullptr ? &r_x_rows : nullptr,
                r_u != nullptr ? &r_u_rows : nullptr);
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
  model->StepJacobians(x, u, StageMode(k), stage_dt_s, x_next, a, b);
  if (k + 1 != retaut_stage) return;
  // chain rule through the jump map: d y / d x = J (d F / d x), d y / d u = J (d F / d u)
  StateMatrix jump;
  *x_next = model->ProjectToTautJacobian(*x_next, &jump);
  *a = (jump * *a).eval();
  *b = (jump * *b).eval();
}

const std::vector<OcpTerm>& OcpTerms() {
  static const std::vector<OcpTerm> terms(kTerms.begin(), kTerms.end());
  return terms;
}

const OcpTerm* FindOcpTerm(std::string_view name) {
  for (const OcpTerm& term : OcpTerms()) {
    if (term.name == name) return &term;
  }
  return nullptr;
}

OcpTermWeight OcpTermStageWeight(const Ocp& ocp, const OcpTerm& term, int k) {
  const bool terminal = k >= ocp.horizon_steps;
  if (terminal && term.at_terminal == OcpTermAtTerminal::kOmitted) {
    return OcpTermWeight::Zero(term.rows);
  }
  double scale = terminal && term.at_terminal == OcpTermAtTerminal::kTimesTerminalFactor
                     ? ocp.weights.terminal_factor
                     : 1.0;
  if (term.scale != nullptr) scale *= term.scale(ocp);
  return scale * term.weight(ocp.weights, ocp.StageMode(k));
}

void EvaluateOcpTerm(const Ocp& ocp, const OcpTerm& term, int k, const StateVector& x,
                     const InputVector& u, Eigen::VectorXd* r, Eigen::MatrixXd* r_x,
                     Eigen::MatrixXd* r_u) {
  ResidualVector r_full = ResidualVector::Zero();
  ResidualStateJacobian r_x_full = ResidualStateJacobian::Zero();
  ResidualInputJacobian r_u_full = ResidualInputJacobian::Zero();
  EvaluateTerm(ocp, term, k, x, u, &r_full, r_x != nullptr ? &r_x_full : nullptr,
               r_u != nullptr ? &r_u_full : nullptr);
  *r = r_full.segment(term.offset, term.rows);
  if (r_x != nullptr) *r_x = r_x_full.middleRows(term.offset, term.rows);
  if (r_u != nullptr) *r_u = r_u_full.middleRows(term.offset, term.rows);
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

void SetCameraDeadzonesAlong(const StateVector& x0, const std::vector<InputVector>& u, Ocp* ocp) {
  ocp->cam_slack_deadzone_stage_m.clear();
  if (ocp->mode != CableMode::kSlack) return;
  const int n = ocp->horizon_steps;
  const double fraction = ocp->weights.cam_slack_deadzone_fraction;
  const Eigen::Vector2d off = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  ocp->cam_slack_deadzone_stage_m.assign(n + 1, off);
  ocp->cam_slack_deadzone_stage_m[0] = ocp->cam_slack_deadzone_m;
  StateVector x = x0;
  for (int k = 0; k < n && k < static_cast<int>(u.size()); ++k) {
    x = ocp->Step(k, x, u[k]);
    if (ocp->StageMode(k + 1) != CableMode::kSlack) continue;  // a scheduled re-taut
    const double depth_m = CostPayloadInCamera(*ocp, k + 1, x).z();
    if (depth_m >= kCamMinDepthM) {
      ocp->cam_slack_deadzone_stage_m[k + 1] = fraction * depth_m * ocp->camera_tan_half_fov;
    }
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
  const Params& params = model->params();
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
  ocp.model = std::move(model);
  return ocp;
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

void StageResidual(const Ocp& ocp, int k, const StateVector& x, const InputVector& u,
                   ResidualVector* r, ResidualStateJacobian* r_x, ResidualInputJacobian* r_u) {
  r->setZero();
  if (r_x != nullptr) r_x->setZero();
  if (r_u != nullptr) r_u->setZero();
  for (const OcpTerm& term : kTerms) EvaluateTerm(ocp, term, k, x, u, r, r_x, r_u);
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
  const int n = ocp.horizon_steps;
  OcpLinearization lin;
  lin.x.resize(n + 1);
  lin.a.resize(n);
  lin.b.resize(n);
  lin.r.resize(n + 1);
  lin.r_x.resize(n + 1);
  lin.r_u.resize(n + 1);
  lin.x[0] = x0;
  double cost = 0.0;
  for (int k = 0; k < n; ++k) {
    StageResidual(ocp, k, lin.x[k], u[k], &lin.r[k], &lin.r_x[k], &lin.r_u[k]);
    cost += lin.r[k].squaredNorm();
    ocp.StepJacobians(k, lin.x[k], u[k], &lin.x[k + 1], &lin.a[k], &lin.b[k]);
  }
  StageResidual(ocp, n, lin.x[n], InputVector::Zero(), &lin.r[n], &lin.r_x[n], &lin.r_u[n]);
  lin.cost = cost + lin.r[n].squaredNorm();
  return lin;
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
