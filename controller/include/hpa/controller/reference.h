#pragma once
// Payload references (hover, line, Lissajous) and their quadrotor counterparts by
// differential flatness: x_Q = x_L - l xi, xi = -(a_L + g e3) / |a_L + g e3|.

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

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

/// One sample of a payload trajectory (a reference file's row, derivatives filled in).
struct TrajectorySample {
  double t_s = 0.0;
  Eigen::Vector3d p_WL_W = Eigen::Vector3d::Zero();  // payload position  (3)
  Eigen::Vector3d v_WL_W = Eigen::Vector3d::Zero();  // payload velocity  (3)
  Eigen::Vector3d a_WL_W = Eigen::Vector3d::Zero();  // payload acceleration  (3)
};

/// A payload trajectory through samples (at least two, strictly increasing times): position,
/// velocity and acceleration linear between samples (the jerk is the acceleration's slope),
/// the first sample held before it, the last one held at rest after it.
std::shared_ptr<Reference> MakeSampledReference(const Params& params,
                                                std::vector<TrajectorySample> samples);

/// Reads a reference CSV: a header naming t_s, x_m, y_m, z_m and optionally vx_mps, vy_mps,
/// vz_mps and ax_mps2, ay_mps2, az_mps2, then one row per sample. Missing velocities and
/// accelerations come from central differences (one-sided at the ends). Throws InputError naming
/// the file, line and column for a missing or unknown column, a short row, a value that is not a
/// finite number, times that do not increase, or fewer than two rows.
std::vector<TrajectorySample> LoadTrajectoryCsv(const std::string& path);

}  // namespace hpa
