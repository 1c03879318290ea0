#include "condensing.h"

namespace hpa {

StageQuadratic GaussNewtonStage(const ResidualVector& r, const ResidualStateJacobian& r_x,
                                const ResidualInputJacobian& r_u) {
  StageQuadratic s;
  // small fixed sizes: coefficient-based products (lazyProduct) beat Eigen's blocked GEMM,
  // which packs its operands (measured with perf: packing + GEMM kernels were ~45% of an RTI)
  s.hxx.noalias() = r_x.transpose().lazyProduct(r_x);
  s.hxu.noalias() = r_x.transpose().lazyProduct(r_u);
  s.huu.noalias() = r_u.transpose().lazyProduct(r_u);
  s.gx.noalias() = r_x.transpose() * r;
  s.gu.noalias() = r_u.transpose() * r;
  return s;
}

void Condense(const std::vector<StateMatrix>& a, const std::vector<InputMatrix>& b,
              const std::vector<StageQuadratic>& stages, Eigen::MatrixXd* h, Eigen::VectorXd* g) {
  const int n = static_cast<int>(a.size());
  h->setZero(kNu * n, kNu * n);
  g->resize(kNu * n);

  // gradient by the adjoint: lambda_N = gx_N, g_k = gu_k + B_k^T lambda_{k+1},
  // lambda_k = gx_k + A_k^T lambda_{k+1}
  StateVector lambda = stages[n].gx;
  for (int k = n - 1; k >= 0; --k) {
    g->segment<kNu>(kNu * k).noalias() = stages[k].gu + b[k].transpose() * lambda;
    lambda = stages[k].gx + a[k].transpose() * lambda;
  }

  // Hessian, one block column j at a time:
  //   G_k = d x_k / d u_j (G_{j+1} = B_j, G_{k+1} = A_k G_k),
  //   W_N = Hxx_N G_N, W_k = Hxx_k G_k + A_k^T W_{k+1},
  //   H_kj = B_k^T W_{k+1} + Hxu_k^T G_k (k > j),  H_jj = Huu_j + B_j^T W_{j+1}.
  std::vector<InputMatrix> sens(n + 1);
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

}  // namespace hpa
