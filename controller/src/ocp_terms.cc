// The stage cost of the OCP as a list of named, weighted residual terms (ocp.h), each with its
// hand-derived Jacobians.

#include <array>
#include <cmath>

#include "hpa/controller/ocp.h"
#include "ocp_internal.h"

namespace hpa {
namespace {

using I = StateIndex;
using ocp_internal::CameraPoint;
using ocp_internal::CameraPointQuatJacobian;
using ocp_internal::RotationOf;
using ocp_internal::SeenPayloadOffset;
using ocp_internal::SlackDeadzoneFraction;
using ocp_internal::StageStateReference;

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
        ocp.StageMode(k) == CableMode::kSlack ? SlackDeadzoneFraction(ocp) : 0.0;
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
  const Eigen::Vector4d q = x.segment<4>(I::kQuat);
  const Eigen::Vector3d p_C = CameraPoint<double>(ocp, d_W, q);
  // d p_C / d x_L = (R R_BC)^T d_d, d p_C / d x_Q = -(R R_BC)^T d_d
  const Eigen::Matrix3d rr = (RotationOf<double>(q(0), q(1), q(2), q(3)) * ocp.R_BC).transpose();
  const Eigen::Matrix3d p_d = rr * d_d;
  for (int i = 0; i < 2; ++i) {
    (*r)(i) = sqrt_cam(i) * p_C(i);
    if (r_x != nullptr) {
      r_x->block<1, 3>(i, I::kPayloadPos) = sqrt_cam(i) * p_d.row(i);
      r_x->block<1, 3>(i, I::kQuadPos) = -sqrt_cam(i) * p_d.row(i);
    }
  }
  if (r_x == nullptr) return;
  const Eigen::Matrix<double, 3, 4> p_q = CameraPointQuatJacobian(ocp, d_W, q);
  for (int i = 0; i < 2; ++i) r_x->block<1, 4>(i, I::kQuat) = sqrt_cam(i) * p_q.row(i);
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

// The stage cost: one line per term (name, rows, terminal role, weight, scale, residual,
// columns).
// m L_load + (1 - m) L_quad is the six state-tracking terms with their per-mode weights.
constexpr OcpTermAtTerminal kTerminalFactor = OcpTermAtTerminal::kTimesTerminalFactor;
constexpr OcpTerm kTermList[] = {
    {"payload_position", 3, kTerminalFactor, &StateWeight<I::kPayloadPos, 3>, nullptr,
     &StateError<I::kPayloadPos, 3>, OcpColumns(I::kPayloadPos, 3)},
    {"payload_velocity", 3, kTerminalFactor, &StateWeight<I::kPayloadVel, 3>, nullptr,
     &StateError<I::kPayloadVel, 3>, OcpColumns(I::kPayloadVel, 3)},
    {"quad_position", 3, kTerminalFactor, &StateWeight<I::kQuadPos, 3>, nullptr,
     &StateError<I::kQuadPos, 3>, OcpColumns(I::kQuadPos, 3)},
    {"quad_velocity", 3, kTerminalFactor, &StateWeight<I::kQuadVel, 3>, nullptr,
     &StateError<I::kQuadVel, 3>, OcpColumns(I::kQuadVel, 3)},
    {"attitude", 4, kTerminalFactor, &StateWeight<I::kQuat, 4>, nullptr, &AttitudeError,
     OcpColumns(I::kQuat, 4)},
    {"body_rate", 3, kTerminalFactor, &StateWeight<I::kBodyRate, 3>, nullptr,
     &StateError<I::kBodyRate, 3>, OcpColumns(I::kBodyRate, 3)},
    {"input", kNu, OcpTermAtTerminal::kOmitted, &InputWeight, nullptr, &InputError,
     OcpColumns(kNx, kNu)},
    // the attitude columns only with the camera at the state's attitude
    {"perception", 2, kTerminalFactor, &PerceptionWeight, &PerceptionScale, &PerceptionError,
     OcpColumns(I::kPayloadPos, 3) | OcpColumns(I::kQuadPos, 3) | OcpColumns(I::kQuat, 4)},
    {"tilt_limit", 1, OcpTermAtTerminal::kAsStage, &TiltWeight, nullptr, &TiltExcess,
     OcpColumns(I::kQuat + 1, 2)},
    {"body_rate_limit", 3, OcpTermAtTerminal::kAsStage, &BodyRateLimitWeight, nullptr,
     &BodyRateExcess, OcpColumns(I::kBodyRate, 3)},
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

const std::vector<OcpTerm>& OcpTerms() {
  static const std::vector<OcpTerm> terms(kTerms.begin(), kTerms.end());
  return terms;
}

const std::array<std::uint32_t, kNr>& OcpResidualColumns() {
  static const std::array<std::uint32_t, kNr> columns = [] {
    std::array<std::uint32_t, kNr> c{};
    for (const OcpTerm& term : kTerms) {
      // a term that declares no columns is looked at in all of them
      const std::uint32_t columns = term.columns != 0 ? term.columns : OcpColumns(0, kNx + kNu);
      for (int i = 0; i < term.rows; ++i) c[term.offset + i] = columns;
    }
    return c;
  }();
  return columns;
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

void StageResidual(const Ocp& ocp, int k, const StateVector& x, const InputVector& u,
                   ResidualVector* r, ResidualStateJacobian* r_x, ResidualInputJacobian* r_u) {
  r->setZero();
  if (r_x != nullptr) r_x->setZero();
  if (r_u != nullptr) r_u->setZero();
  for (const OcpTerm& term : kTerms) EvaluateTerm(ocp, term, k, x, u, r, r_x, r_u);
}

}  // namespace hpa
