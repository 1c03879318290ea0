#pragma once
// The analytic hybrid model of the paper's section III: taut flow g_p, slack flow g_z, their
// RK4 discretisation and exact Jacobians (forward-mode automatic differentiation).

#include <Eigen/Core>

#include "hpa/models/params.h"
#include "hpa/models/state.h"

namespace hpa {

using StateMatrix = Eigen::Matrix<double, kNx, kNx>;
using InputMatrix = Eigen::Matrix<double, kNx, kNu>;

/// Hybrid model: continuous dynamics per mode, one-step discretisation and sensitivities.
///
/// Taut flow (paper eqs. 5-8) is written with the cable tension T along xi = (x_L - x_Q)/|.|:
///   m_L (a_L + g e3) = -T xi,   m (a_Q + g e3) = f R e3 + T xi,
///   T = m m_L / (m + m_L) * (|v_perp|^2 / d - xi . f R e3 / m + k_d v_r + k_p (d - l)),
/// which equals the paper's Lagrange-d'Alembert form when d = l and v_r = 0; the k_p, k_d terms
/// (Baumgarte stabilisation) hold the cable length against integration drift.
/// Slack flow (paper eqs. 10-11): payload in free fall, quadrotor free.
class HybridModel {
 public:
  /// Uses the flight code's parameters (masses, cable length, rotor constants, inertia).
  explicit HybridModel(const Params& params);

  /// Continuous-time dynamics x_dot = g_p(x, u) (taut) or g_z(x, u) (slack). u: rotor speeds.
  StateVector Derivative(const StateVector& x, const InputVector& u, CableMode mode) const;

  /// Derivative and its Jacobians d x_dot / d x (19x19) and d x_dot / d u (19x4).
  void DerivativeJacobians(const StateVector& x, const InputVector& u, CableMode mode,
                           StateVector* x_dot, StateMatrix* a, InputMatrix* b) const;

  /// One RK4 step of dt_s with u held, quaternion renormalised at the end.
  StateVector Step(const StateVector& x, const InputVector& u, CableMode mode, double dt_s) const;

  /// Step and its exact sensitivities (through RK4 and the renormalisation).
  void StepJacobians(const StateVector& x, const InputVector& u, CableMode mode, double dt_s,
                     StateVector* x_next, StateMatrix* a, InputMatrix* b) const;

  /// The jump map a cable can give (docs/design.md section 4): positions moved along xi, keeping the
  /// centre of mass, only as far as the taut band l - epsilon <= |x_L - x_Q| <= l requires;
  /// a payload moving away along xi stopped by a perfectly inelastic collision (momentum kept),
  /// an approaching one left alone (a cable cannot push). Applied to a state just past the
  /// guard (re-taut, or an estimate off the constraint) before the taut model predicts.
  StateVector ProjectToTaut(const StateVector& x) const;

  /// ProjectToTaut and its exact Jacobian d y / d x (19x19), piecewise as the map is.
  StateVector ProjectToTautJacobian(const StateVector& x, StateMatrix* jacobian) const;

  /// Cable tension (N) that the taut model implies at x under u.
  double TautTensionN(const StateVector& x, const InputVector& u) const;

  /// A taut equilibrium: quadrotor at p_WQ_W, level, payload hanging l below, at rest.
  StateVector HoverState(const Eigen::Vector3d& p_WQ_W) const;

  const Params& params() const { return params_; }

  static constexpr double kBaumgarteStiffness = 25.0;  // 1/s^2: omega = 5 rad/s
  static constexpr double kBaumgarteDamping = 10.0;    // 1/s: critically damped

 private:
  Params params_;
  Eigen::Matrix4d allocation_;  // rotor thrusts -> [f, M]
};

}  // namespace hpa
