#include "hpa/controller/reference.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hpa {
namespace {

// Payload derivatives 0..4 (position, velocity, acceleration, jerk, snap), world frame.
struct PayloadDerivatives {
  Eigen::Vector3d d[5];
};

// Minimum-jerk blend s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5 and its derivatives in tau (0..3).
void MinJerk(double tau, double s[4]) {
  if (tau <= 0.0) {
    s[0] = s[1] = s[2] = s[3] = 0.0;
    return;
  }
  if (tau >= 1.0) {
    s[0] = 1.0;
    s[1] = s[2] = s[3] = 0.0;
    return;
  }
  const double t2 = tau * tau, t3 = t2 * tau, t4 = t3 * tau, t5 = t4 * tau;
  s[0] = 10 * t3 - 15 * t4 + 6 * t5;
  s[1] = 30 * t2 - 60 * t3 + 30 * t4;
  s[2] = 60 * tau - 180 * t2 + 120 * t3;
  s[3] = 60 - 360 * tau + 360 * t2;
}

// Builds the flat quadrotor output from payload derivatives:
// xi = -n / |n| with n = a_L + g e3, x_Q = x_L - l xi (and two time derivatives).
ReferencePoint FlatOutput(const Params& params, const PayloadDerivatives& pd) {
  ReferencePoint r;
  r.p_WL_W = pd.d[0];
  r.v_WL_W = pd.d[1];
  r.a_WL_W = pd.d[2];
  r.j_WL_W = pd.d[3];
  const Eigen::Vector3d n = pd.d[2] + Eigen::Vector3d(0, 0, params.gravity_mps2);
  const Eigen::Vector3d n1 = pd.d[3];
  const Eigen::Vector3d n2 = pd.d[4];
  // unit vector u = n / rho and its derivatives: u' = (n' - u rho') / rho,
  // u'' = (n'' - 2 u' rho' - u rho'') / rho, rho' = u.n', rho'' = u'.n' + u.n''
  const double rho = n.norm();
  const Eigen::Vector3d u = n / rho;
  const double rho1 = u.dot(n1);
  const Eigen::Vector3d u1 = (n1 - u * rho1) / rho;
  const double rho2 = u1.dot(n1) + u.dot(n2);
  const Eigen::Vector3d u2 = (n2 - 2.0 * u1 * rho1 - u * rho2) / rho;
  const double l = params.cable_length_m;
  r.xi_W = -u;
  r.p_WQ_W = pd.d[0] + l * u;
  r.v_WQ_W = pd.d[1] + l * u1;
  r.a_WQ_W = pd.d[2] + l * u2;
  return r;
}

// Constant payload position.
class HoverReference : public Reference {
 public:
  HoverReference(const Params& params, const Eigen::Vector3d& p_WL_W)
      : point_(Compute(params, p_WL_W)) {}
  ReferencePoint At(double /*t_s*/) const override { return point_; }

 private:
  static ReferencePoint Compute(const Params& params, const Eigen::Vector3d& p_WL_W) {
    PayloadDerivatives pd;
    pd.d[0] = p_WL_W;
    for (int i = 1; i < 5; ++i) pd.d[i].setZero();
    return FlatOutput(params, pd);
  }
  ReferencePoint point_;
};

// Minimum-jerk straight line.
class LineReference : public Reference {
 public:
  LineReference(const Params& params, const Eigen::Vector3d& start, const Eigen::Vector3d& end,
                double duration_s)
      : params_(params), start_(start), end_(end), duration_s_(duration_s) {}

  ReferencePoint At(double t_s) const override {
    double s[4];
    MinJerk(t_s / duration_s_, s);
    // 4th derivative of s in tau: s'''' = -360 + 720 tau inside the motion
    const double tau = t_s / duration_s_;
    const double s4 = (tau > 0.0 && tau < 1.0) ? (-360.0 + 720.0 * tau) : 0.0;
    const Eigen::Vector3d delta = end_ - start_;
    PayloadDerivatives pd;
    pd.d[0] = start_ + s[0] * delta;
    double scale = 1.0;
    for (int i = 1; i < 5; ++i) {
      scale /= duration_s_;
      pd.d[i] = (i < 4 ? s[i] : s4) * scale * delta;
    }
    return FlatOutput(params_, pd);
  }

 private:
  Params params_;
  Eigen::Vector3d start_, end_;
  double duration_s_;
};

// Lissajous with a smoothly ramped phase theta(t): theta' = w s(t / ramp), s minimum-jerk.
class LissajousReference : public Reference {
 public:
  LissajousReference(const Params& params, const LissajousSpec& spec)
      : params_(params), spec_(spec) {}

  ReferencePoint At(double t_s) const override {
    // phase theta and its time derivatives th[0..4]
    const double w = 2.0 * M_PI / spec_.period_s;
    const double ramp = spec_.ramp_s;
    double th[5] = {0, 0, 0, 0, 0};
    if (t_s > 0.0) {
      if (ramp > 0.0 && t_s < ramp) {
        const double tau = t_s / ramp;
        const double t4 = std::pow(tau, 4), t5 = t4 * tau, t6 = t5 * tau;
        double s[4];
        MinJerk(tau, s);
        th[0] = w * ramp * (2.5 * t4 - 3.0 * t5 + t6);  // w * integral of s
        th[1] = w * s[0];
        th[2] = w * s[1] / ramp;
        th[3] = w * s[2] / (ramp * ramp);
        th[4] = w * s[3] / (ramp * ramp * ramp);
      } else {
        th[0] = w * (0.5 * std::max(ramp, 0.0) + (t_s - std::max(ramp, 0.0)));
        th[1] = w;
      }
    }
    // derivatives of f(theta) per axis: amplitude A, frequency k, phase offset p:
    // f^(i) = A k^i sin(k theta + p + i pi / 2)
    const double amp[3] = {spec_.a, spec_.b, spec_.c};
    const double freq[3] = {1.0, spec_.n, spec_.m};
    const double offset[3] = {0.0, spec_.phi, 0.0};
    Eigen::Vector3d f[5];
    for (int i = 0; i < 5; ++i) {
      for (int axis = 0; axis < 3; ++axis) {
        f[i](axis) = amp[axis] * std::pow(freq[axis], i) *
                     std::sin(freq[axis] * th[0] + offset[axis] + i * M_PI / 2.0);
      }
    }
    // chain rule (Faa di Bruno) up to the 4th derivative
    PayloadDerivatives pd;
    pd.d[0] = f[0] + Eigen::Vector3d(0, 0, spec_.psi) + spec_.centre;
    pd.d[1] = f[1] * th[1];
    pd.d[2] = f[2] * th[1] * th[1] + f[1] * th[2];
    pd.d[3] = f[3] * std::pow(th[1], 3) + 3.0 * f[2] * th[1] * th[2] + f[1] * th[3];
    pd.d[4] = f[4] * std::pow(th[1], 4) + 6.0 * f[3] * th[1] * th[1] * th[2] +
              f[2] * (3.0 * th[2] * th[2] + 4.0 * th[1] * th[3]) + f[1] * th[4];
    return FlatOutput(params_, pd);
  }

 private:
  Params params_;
  LissajousSpec spec_;
};

}  // namespace

std::shared_ptr<Reference> MakeHoverReference(const Params& params, const Eigen::Vector3d& p_WL_W) {
  if (!p_WL_W.allFinite()) throw std::invalid_argument("hover reference: non-finite position");
  return std::make_shared<HoverReference>(params, p_WL_W);
}

std::shared_ptr<Reference> MakeLineReference(const Params& params, const Eigen::Vector3d& start,
                                             const Eigen::Vector3d& end, double duration_s) {
  if (!(duration_s > 0.0) || !start.allFinite() || !end.allFinite()) {
    throw std::invalid_argument("line reference: need finite ends and duration > 0");
  }
  return std::make_shared<LineReference>(params, start, end, duration_s);
}

std::shared_ptr<Reference> MakeLissajousReference(const Params& params, const LissajousSpec& spec) {
  if (!(spec.period_s > 0.0) || !(spec.ramp_s >= 0.0)) {
    throw std::invalid_argument("lissajous reference: need period_s > 0 and ramp_s >= 0");
  }
  return std::make_shared<LissajousReference>(params, spec);
}

namespace {

// Payload trajectory through samples, linear in p, v and a between them.
class SampledReference : public Reference {
 public:
  SampledReference(const Params& params, std::vector<TrajectorySample> samples)
      : params_(params), samples_(std::move(samples)) {}

  ReferencePoint At(double t_s) const override {
    PayloadDerivatives pd;
    for (Eigen::Vector3d& d : pd.d) d.setZero();
    if (t_s <= samples_.front().t_s) {
      const TrajectorySample& s = samples_.front();
      pd.d[0] = s.p_WL_W, pd.d[1] = s.v_WL_W, pd.d[2] = s.a_WL_W;
      return FlatOutput(params_, pd);
    }
    if (t_s >= samples_.back().t_s) {
      pd.d[0] = samples_.back().p_WL_W;  // at rest after the file ends
      return FlatOutput(params_, pd);
    }
    const auto after = std::upper_bound(
        samples_.begin(), samples_.end(), t_s,
        [](double t, const TrajectorySample& s) { return t < s.t_s; });
    const TrajectorySample& b = *after;
    const TrajectorySample& a = *(after - 1);
    const double h = b.t_s - a.t_s, w = (t_s - a.t_s) / h;
    pd.d[0] = a.p_WL_W + w * (b.p_WL_W - a.p_WL_W);
    pd.d[1] = a.v_WL_W + w * (b.v_WL_W - a.v_WL_W);
    pd.d[2] = a.a_WL_W + w * (b.a_WL_W - a.a_WL_W);
    pd.d[3] = (b.a_WL_W - a.a_WL_W) / h;
    return FlatOutput(params_, pd);
  }

 private:
  Params params_;
  std::vector<TrajectorySample> samples_;
};

}  // namespace

std::shared_ptr<Reference> MakeSampledReference(const Params& params,
                                                std::vector<TrajectorySample> samples) {
  if (samples.size() < 2) throw std::invalid_argument("a sampled reference needs two samples");
  return std::make_shared<SampledReference>(params, std::move(samples));
}

}  // namespace hpa
