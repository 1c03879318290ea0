#pragma once
// Payload references (hover, line, Lissajous) and their quadrotor counterparts by
// differential flatness: x_Q = x_L - l xi, xi = -(a_L + g e3) / |a_L + g e3|.

#include <Eigen/Core>
#include <memory>

#include "hpa/models/params.h"

namespace hpa {

/// Reference at one instant: payload trajectory with derivatives and the flat quadrotor output.
struct ReferencePoint {
  Eigen::Vector3d p_WL_W = Eigen::Vector3d::Zero();  // payload position  (3)
  Eigen::Vector3d v_WL_W = Eigen::Vector3d::Zero();  // payload velocity  (3)
  Eigen::Vector3d a_WL_W = Eigen::Vector3d::Zero();  // payload acceleration  (3)
  Eigen::Vector3d j_WL_W = Eigen::Vector3d::Zero();  // payload jerk  (3)
  Eigen::Vector3d xi_W = Eigen::Vector3d(0, 0, -1);  // cable direction, quad -> payload  (3)
  Eigen::Vector3d p_WQ_W = Eigen::Vector3d::Zero();  // quadrotor position  (3)
  Eigen::Vector3d v_WQ_W = Eigen::Vector3d::Zero();  // quadrotor velocity  (3)
  Eigen::Vector3d a_WQ_W = Eigen::Vector3d::Zero();  // quadrotor acceleration  (3)
};

/// A payload trajectory; At() is analytic (no numerical differentiation).
class Reference {
 public:
  virtual ~Reference() = default;
  /// The reference at time t_s (payload derivatives and flat quadrotor output).
  virtual ReferencePoint At(double t_s) const = 0;
};

/// Constant payload position.
std::shared_ptr<Reference> MakeHoverReference(const Params& params, const Eigen::Vector3d& p_WL_W);

/// Straight line from start to end over duration_s with a smooth (minimum-jerk) time law,
/// holding start before t = 0 and end after.
std::shared_ptr<Reference> MakeLineReference(const Params& params, const Eigen::Vector3d& start,
                                             const Eigen::Vector3d& end, double duration_s);

/// The paper's Lissajous: x_L = [a sin(wt), b sin(n wt + phi), c sin(m wt) + psi], w = 2 pi / T,
/// plus `centre` (world). The phase w t is replaced by a phase whose rate ramps smoothly from 0
/// to w over the first ramp_s seconds (C2, analytic), so the payload starts at rest.
struct LissajousSpec {
  double a = 2.0, b = 0.5, c = 0.0, n = 2.0, m = 1.0, phi = 0.0, psi = 1.0;
  double period_s = 5.0;
  double ramp_s = 2.0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
};
std::shared_ptr<Reference> MakeLissajousReference(const Params& params, const LissajousSpec& spec);

}  // namespace hpa
