#include "condensing.h"

#include <array>
#include <cstdint>

namespace hpa {
namespace {

// The condensed gradient by the adjoint: lambda_N = gx_N, g_k = gu_k + B_k^T lambda_{k+1},
// lambda_k = gx_k + A_k^T lambda_{k+1} (g already sized kNu n).
void CondensedGradient(const std::vector<StateMatrix>& a, const std::vector<InputMatrix>& b,
                       const std::vector<StageQuadratic>& stages, Eigen::VectorXd* g) {
  const int n = static_cast<int>(a.size());
  StateVector lambda = stages[n].gx;
  for (int k = n - 1; k >= 0; --k) {
    g->segment<kNu>(kNu * k).noalias() = stages[k].gu + b[k].transpose() * lambda;
    lambda = stages[k].gx + a[k].transpose() * lambda;
  }
}

}  // namespace

StageQuadratic GaussNewtonStage(const ResidualVector& r, const ResidualStateJacobian& r_x,
                                const ResidualInputJacobian& r_u) {
  std::array<std::uint32_t, kNr> every_column;
  every_column.fill(OcpColumns(0, kNx + kNu));
  StageQuadratic s;
  GaussNewtonStage(r, r_x, r_u, every_column, &s);
  return s;
}

void GaussNewtonStage(const ResidualVector& r, const ResidualStateJacobian& r_x,
                      const ResidualInputJacobian& r_u,
                      const std::array<std::uint32_t, kNr>& row_columns, StageQuadratic* s) {
  // Each residual row touches few of the 23 variables (a state-tracking row one, L_cam six): the
  // sums H = sum_i j_i^T j_i and g = sum_i j_i r_i run over each row's nonzeros only, looked for
  // among the row's candidate columns (in increasing order, as a scan of all would find them).
  Eigen::Matrix<double, kNx + kNu, kNx + kNu> h =
      Eigen::Matrix<double, kNx + kNu, kNx + kNu>::Zero();
  Eigen::Matrix<double, kNx + kNu, 1> g = Eigen::Matrix<double, kNx + kNu, 1>::Zero();
  std::array<int, kNx + kNu> cols;
  std::array<double, kNx + kNu> vals;
  for (int i = 0; i < kNr; ++i) {
    int n = 0;
    for (std::uint32_t m = row_columns[i]; m != 0; m &= m - 1) {
      const int c = __builtin_ctz(m);  // the lowest candidate column left
      const double v = c < kNx ? r_x(i, c) : r_u(i, c - kNx);
      if (v != 0.0) cols[n] = c, vals[n++] = v;
    }
    for (int a = 0; a < n; ++a) {
      g(cols[a]) += vals[a] * r(i);
      for (int b = 0; b < n; ++b) h(cols[a], cols[b]) += vals[a] * vals[b];
    }
  }
  s->hxx = h.topLeftCorner<kNx, kNx>();
  s->hxu = h.topRightCorner<kNx, kNu>();
  s->huu = h.bottomRightCorner<kNu, kNu>();
  s->gx = g.head<kNx>();
  s->gu = g.tail<kNu>();
}

void Condense(const std::vector<StateMatrix>& a, const std::vector<InputMatrix>& b,
              const std::vector<StageQuadratic>& stages, Eigen::MatrixXd* h, Eigen::VectorXd* g) {
  CondensingWorkspace workspace;
  Condense(a, b, stages, &workspace, h, g);
}

void Condense(const std::vector<StateMatrix>& a, const std::vector<InputMatrix>& b,
              const std::vector<StageQuadratic>& stages, CondensingWorkspace* workspace,
              Eigen::MatrixXd* h, Eigen::VectorXd* g) {
  const int n = static_cast<int>(a.size());
  h->setZero(kNu * n, kNu * n);
  g->resize(kNu * n);

  CondensedGradient(a, b, stages, g);

  // Hessian, one block column j at a time:
  //   G_k = d x_k / d u_j (G_{j+1} = B_j, G_{k+1} = A_k G_k),
  //   W_N = Hxx_N G_N, W_k = Hxx_k G_k + A_k^T W_{k+1},
  //   H_kj = B_k^T W_{k+1} + Hxu_k^T G_k (k > j),  H_jj = Huu_j + B_j^T W_{j+1}.
  std::vector<InputMatrix>& sens = workspace->sens;
  sens.resize(n + 1);
  for (int j = 0; j < n; ++j) {
    sens[j + 1] = b[j];
    for (int k = j + 1; k < n; ++k) sens[k + 1].noalias() = a[k].lazyProduct(sens[k]);
    InputMatrix w;
    w.noalias() = stages[n].hxx.lazyProduct(sens[n]);
    for (int k = n - 1; k > j; --k) {
      Eigen::Matrix<double, kNu, kNu> h_kj;
      h_kj.noalias() = b[k].transpose().lazyProduct(w);
      h_kj.noalias() += stages[k].hxu.transpose().lazyProduct(sens[k]);
      h->block<kNu, kNu>(kNu * k, kNu * j) = h_kj;
      h->block<kNu, kNu>(kNu * j, kNu * k) = h_kj.transpose();
      InputMatrix w_next;
      w_next.noalias() = stages[k].hxx.lazyProduct(sens[k]);
      w_next.noalias() += a[k].transpose().lazyProduct(w);
      w = w_next;
    }
    Eigen::Matrix<double, kNu, kNu> h_jj = stages[j].huu;
    h_jj.noalias() += b[j].transpose().lazyProduct(w);
    h->block<kNu, kNu>(kNu * j, kNu * j) = 0.5 * (h_jj + h_jj.transpose());
  }
}

namespace {

using I = StateIndex;

// The rigid body's pattern in A: attitude and rate rows free of the position and velocity
// columns, rate rows free of the attitude columns.
bool AttitudeDecoupled(const StateMatrix& a) {
  return a.block<kNx - I::kQuat, I::kQuat>(I::kQuat, 0).isZero(0.0) &&
         a.block<kNx - I::kBodyRate, 4>(I::kBodyRate, I::kQuat).isZero(0.0);
}

// out = A x, skipping the zero blocks of AttitudeDecoupled when `decoupled`.
void MulA(const StateMatrix& a, bool decoupled, const InputMatrix& x, InputMatrix* out) {
  if (!decoupled) {
    out->noalias() = a.lazyProduct(x);
    return;
  }
  constexpr int kRot = kNx - I::kQuat, kRate = kNx - I::kBodyRate;
  out->topRows<I::kQuat>().noalias() = a.topRows<I::kQuat>().lazyProduct(x);
  out->middleRows<4>(I::kQuat).noalias() =
      a.block<4, kRot>(I::kQuat, I::kQuat).lazyProduct(x.bottomRows<kRot>());
  out->bottomRows<kRate>().noalias() =
      a.bottomRightCorner<kRate, kRate>().lazyProduct(x.bottomRows<kRate>());
}

// out = A^T x, skipping the same zero blocks.
void MulAt(const StateMatrix& a, bool decoupled, const InputMatrix& x, InputMatrix* out) {
  if (!decoupled) {
    out->noalias() = a.transpose().lazyProduct(x);
    return;
  }
  constexpr int kRate = kNx - I::kBodyRate;
  out->topRows<I::kQuat>().noalias() =
      a.topLeftCorner<I::kQuat, I::kQuat>().transpose().lazyProduct(x.topRows<I::kQuat>());
  out->middleRows<4>(I::kQuat).noalias() =
      a.block<I::kBodyRate, 4>(0, I::kQuat).transpose().lazyProduct(x.topRows<I::kBodyRate>());
  out->bottomRows<kRate>().noalias() = a.rightCols<kRate>().transpose().lazyProduct(x);
}

// out += Hxx x over the stored nonzeros of Hxx (stored row by row): each row of out is loaded
// once and takes its row's products in increasing column order.
void AddSparseTimes(const std::vector<SparseEntry>& m, const InputMatrix& x, InputMatrix* out) {
  for (size_t e = 0; e < m.size();) {
    const int row = m[e].row;
    Eigen::Matrix<double, 1, kNu> out_row = out->row(row);
    for (; e < m.size() && m[e].row == row; ++e) out_row += m[e].value * x.row(m[e].col);
    out->row(row) = out_row;
  }
}

// Sizes the workspace and records each stage's structure.
void AnalyseStructure(const std::vector<StateMatrix>& a, const std::vector<StageQuadratic>& stages,
                      CondensingWorkspace* ws) {
  const int n = static_cast<int>(a.size());
  ws->sens.resize(n + 1);
  ws->hxx.resize(n + 1);
  ws->hxu_zero.resize(n + 1);
  ws->attitude_decoupled.resize(n);
  for (int k = 0; k <= n; ++k) {
    std::vector<SparseEntry>& entries = ws->hxx[k];
    entries.reserve(kNx * kNx);
    entries.clear();
    for (int r = 0; r < kNx; ++r) {
      for (int c = 0; c < kNx; ++c) {
        if (stages[k].hxx(r, c) != 0.0) entries.push_back({r, c, stages[k].hxx(r, c)});
      }
    }
    ws->hxu_zero[k] = stages[k].hxu.isZero(0.0);
    if (k < n) ws->attitude_decoupled[k] = AttitudeDecoupled(a[k]);
  }
}

}  // namespace

void CondenseStructured(const std::vector<StateMatrix>& a, const std::vector<InputMatrix>& b,
                        const std::vector<StageQuadratic>& stages, CondensingWorkspace* ws,
                        Eigen::MatrixXd* h, Eigen::VectorXd* g) {
  const int n = static_cast<int>(a.size());
  AnalyseStructure(a, stages, ws);
  h->resize(kNu * n, kNu * n);  // every block is written below
  g->resize(kNu * n);
  CondensedGradient(a, b, stages, g);
  // Hessian one block column j at a time, the recursions of Condense
  std::vector<InputMatrix>& sens = ws->sens;
  InputMatrix w, w_next;
  for (int j = 0; j < n; ++j) {
    sens[j + 1] = b[j];
    for (int k = j + 1; k < n; ++k) MulA(a[k], ws->attitude_decoupled[k], sens[k], &sens[k + 1]);
    w.setZero();
    AddSparseTimes(ws->hxx[n], sens[n], &w);
    for (int k = n - 1; k > j; --k) {
      Eigen::Matrix<double, kNu, kNu> h_kj;
      h_kj.noalias() = b[k].transpose().lazyProduct(w);
      if (!ws->hxu_zero[k]) h_kj.noalias() += stages[k].hxu.transpose().lazyProduct(sens[k]);
      h->block<kNu, kNu>(kNu * k, kNu * j) = h_kj;
      h->block<kNu, kNu>(kNu * j, kNu * k) = h_kj.transpose();
      MulAt(a[k], ws->attitude_decoupled[k], w, &w_next);
      AddSparseTimes(ws->hxx[k], sens[k], &w_next);
      w = w_next;
    }
    Eigen::Matrix<double, kNu, kNu> h_jj = stages[j].huu;
    h_jj.noalias() += b[j].transpose().lazyProduct(w);
    h->block<kNu, kNu>(kNu * j, kNu * j) = 0.5 * (h_jj + h_jj.transpose());
  }
}

}  // namespace hpa
