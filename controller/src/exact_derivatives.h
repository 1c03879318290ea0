#pragma once
// Private to the controller library. Hand-derived exact derivatives of the hybrid model as the
// OCP uses it: the continuous flow (taut and slack), its RK4 step (chain rule through the four
// stages and the quaternion renormalisation) and the jump map. They compute what
// HybridModel::DerivativeJacobians / StepJacobians / ProjectToTautJacobian compute by forward-mode
// automatic differentiation, without carrying 23 derivatives through every scalar operation, and
// they skip the structural zeros of the flow Jacobian. Values come from HybridModel itself, so
// x_next is bit-identical to HybridModel::Step.

#include <Eigen/Core>

#include "hpa/models/hybrid_model.h"

namespace hpa {

/// Columns of a sensitivity d(state) / d(x, u): the 19 states, then the 4 rotor speeds.
constexpr int kNxu = kNx + kNu;
using StepSensitivity = Eigen::Matrix<double, kNx, kNxu>;

/// The non-trivial blocks of the flow Jacobian d x_dot / d(x, u), in the flow's own factors. The
/// rest is structural: d p_dot / d v = I for payload and quadrotor, zeros elsewhere. With T xi
/// the cable force on the quadrotor (taut; zero in slack) and f = f R e3 the thrust vector:
/// a_L = -T xi / m_L - g e3, a_Q = (f + T xi) / m - g e3; T xi depends on the state through
/// r = p_L - p_Q, v = v_L - v_Q and q only.
struct FlowJacobian {
  bool taut = true;                                   // the cable-force blocks apply
  double inv_payload_mass_per_kg = 0.0;               // 1 / m_L
  double inv_quad_mass_per_kg = 0.0;                  // 1 / m
  Eigen::Matrix3d cable_r = Eigen::Matrix3d::Zero();  // d (T xi) / dr
  Eigen::Matrix3d cable_v = Eigen::Matrix3d::Zero();  // d (T xi) / dv
  Eigen::Matrix<double, 3, 4> cable_q = Eigen::Matrix<double, 3, 4>::Zero();       // d (T xi) / dq
  Eigen::Matrix<double, 3, kNu> cable_u = Eigen::Matrix<double, 3, kNu>::Zero();   // d (T xi) / du
  Eigen::Matrix<double, 3, 4> thrust_q = Eigen::Matrix<double, 3, 4>::Zero();      // d f / dq
  Eigen::Matrix<double, 3, kNu> thrust_u = Eigen::Matrix<double, 3, kNu>::Zero();  // d f / du
  Eigen::Matrix4d qdot_q = Eigen::Matrix4d::Zero();                                // d q_dot / d q
  Eigen::Matrix<double, 4, 3> qdot_w = Eigen::Matrix<double, 4, 3>::Zero();      // d q_dot / d w_B
  Eigen::Matrix3d wdot_w = Eigen::Matrix3d::Zero();                              // d w_dot / d w_B
  Eigen::Matrix<double, 3, kNu> wdot_u = Eigen::Matrix<double, 3, kNu>::Zero();  // d w_dot / du
};

/// The part of the flow Jacobian that depends on the rotor speeds only (the rotor map), the same
/// at every RK4 stage of a step.
struct RotorJacobian {
  double thrust_N = 0.0;                                                           // collective f
  Eigen::Matrix<double, 1, kNu> thrust_u = Eigen::Matrix<double, 1, kNu>::Zero();  // d f / du
  Eigen::Matrix<double, 3, kNu> wdot_u = Eigen::Matrix<double, 3, kNu>::Zero();    // d w_dot / du
};

/// The rotor map's part of the flow Jacobian at u; allocation: AllocationMatrix(params).
RotorJacobian EvaluateRotorJacobian(const Params& params, const Eigen::Matrix4d& allocation,
                                    const InputVector& u);

/// The flow Jacobian at x in `mode`, with the rotor part `rotor` of the input.
void EvaluateFlowJacobian(const Params& params, const RotorJacobian& rotor, const StateVector& x,
                          CableMode mode, FlowJacobian* jacobian);

/// The flow Jacobian at (x, u) in `mode`; allocation: AllocationMatrix(params).
void EvaluateFlowJacobian(const Params& params, const Eigen::Matrix4d& allocation,
                          const StateVector& x, const InputVector& u, CableMode mode,
                          FlowJacobian* jacobian);

/// The flow Jacobian as dense matrices a = d x_dot / dx (19 x 19), b = d x_dot / du (19 x 4).
void DenseFlowJacobian(const FlowJacobian& jacobian, StateMatrix* a, InputMatrix* b);

/// The flow Jacobian as one sensitivity k = [d x_dot / dx, d x_dot / du] (19 x 23): what
/// ApplyFlowJacobian gives for s = I, without its products.
void FlowJacobianMatrix(const FlowJacobian& jacobian, StepSensitivity* k);

/// k = J s + [0 B]: the flow Jacobian applied to a sensitivity (what one RK4 stage needs). s must
/// have the rigid body's pattern, as the identity and every RK4 stage sensitivity have: its
/// attitude rows zero in the position and velocity columns, its rate rows zero in those and the
/// attitude columns (the rotation does not depend on the translation); k has it too.
void ApplyFlowJacobian(const FlowJacobian& jacobian, const StepSensitivity& s, StepSensitivity* k);

/// model.Step (one RK4 step of dt_s, quaternion renormalised) and its exact Jacobians
/// a = d x_next / dx (19 x 19), b = d x_next / du (19 x 4).
void ExactStepJacobians(const HybridModel& model, const StateVector& x, const InputVector& u,
                        CableMode mode, double dt_s, StateVector* x_next, StateMatrix* a,
                        InputMatrix* b);

/// model.ProjectToTaut (the jump map) and its exact Jacobian d y / dx (19 x 19), piecewise as
/// the map is (the AD path's branches).
StateVector ExactJumpJacobian(const HybridModel& model, const StateVector& x,
                              StateMatrix* jacobian);

}  // namespace hpa
