#pragma once
// Private to the controller library (RTI). Condensing of a linearised OCP onto its inputs (single
// shooting, dx_0 = 0):
//   dx_{k+1} = A_k dx_k + B_k du_k,
//   cost = sum_k 1/2 [dx;du]^T [Hxx Hxu; Hxu^T Huu] [dx;du] + gx^T dx + gu^T du  (+ terminal)
// becomes the dense QP  min 1/2 du^T H du + g^T du  over du = [du_0 .. du_{N-1}].

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "hpa/controller/ocp.h"
#include "hpa/models/hybrid_model.h"

namespace hpa {

/// Quadratic model of one stage's cost around the current trajectory.
struct StageQuadratic {
  StateMatrix hxx = StateMatrix::Zero();                                          // (19 x 19)
  Eigen::Matrix<double, kNx, kNu> hxu = Eigen::Matrix<double, kNx, kNu>::Zero();  // (19 x 4)
  Eigen::Matrix<double, kNu, kNu> huu = Eigen::Matrix<double, kNu, kNu>::Zero();  // (4 x 4)
  StateVector gx = StateVector::Zero();                                           // (19)
  InputVector gu = InputVector::Zero();                                           // (4)
};

/// Gauss-Newton model of |r + R_x dx + R_u du|^2 / 2: H = J^T J, g = J^T r.
StageQuadratic GaussNewtonStage(const ResidualVector& r, const ResidualStateJacobian& r_x,
                                const ResidualInputJacobian& r_u);

/// GaussNewtonStage into `stage` (every member written), where row i of [R_x R_u] is nonzero only
/// in the columns of row_columns[i] (OcpColumns bits, e.g. OcpResidualColumns()): the same
/// result, found without looking at the other columns.
void GaussNewtonStage(const ResidualVector& r, const ResidualStateJacobian& r_x,
                      const ResidualInputJacobian& r_u,
                      const std::array<std::uint32_t, kNr>& row_columns, StageQuadratic* stage);

/// Condenses N stages (a, b: N each; stages: N + 1, the last one terminal, its u-blocks
/// ignored) into h (4N x 4N) and g (4N). O(N^2) block operations, no dense sensitivity matrix.
void Condense(const std::vector<StateMatrix>& a, const std::vector<InputMatrix>& b,
              const std::vector<StageQuadratic>& stages, Eigen::MatrixXd* h, Eigen::VectorXd* g);

/// One stored entry of a sparse stage Hessian block.
struct SparseEntry {
  int row = 0;
  int col = 0;
  double value = 0.0;
};

/// Scratch of Condense and CondenseStructured, kept between calls: sized on the first call, then
/// reused without allocating.
struct CondensingWorkspace {
  std::vector<InputMatrix> sens;              // d x_k / d u_j for one j  (N + 1)
  std::vector<std::vector<SparseEntry>> hxx;  // nonzeros of each stage's Hxx, by row  (N + 1)
  std::vector<char> hxu_zero;                 // stage's Hxu is all zero  (N + 1)
  std::vector<char> attitude_decoupled;       // A_k's pattern, see CondenseStructured  (N)
};

/// Condense with its scratch in `workspace` (no heap allocation once sized).
void Condense(const std::vector<StateMatrix>& a, const std::vector<InputMatrix>& b,
              const std::vector<StageQuadratic>& stages, CondensingWorkspace* workspace,
              Eigen::MatrixXd* h, Eigen::VectorXd* g);

/// Condense with the same result as `Condense` up to rounding, exploiting the structure of this
/// OCP: the stage Hessians' zeros (Hxx nearly diagonal, Hxu zero when no residual row couples
/// states and inputs), and, where A_k has it, the rigid body's pattern: the attitude and rate
/// rows do not depend on positions and velocities, and the rate rows not on the attitude.
/// Both are detected from the values (exact zeros), so any A_k and stage model are handled.
void CondenseStructured(const std::vector<StateMatrix>& a, const std::vector<InputMatrix>& b,
                        const std::vector<StageQuadratic>& stages, CondensingWorkspace* workspace,
                        Eigen::MatrixXd* h, Eigen::VectorXd* g);

}  // namespace hpa
