#pragma once
// Payload references (hover, line, Lissajous) and their quadrotor counterparts by
// differential flatness: x_Q = x_L - l xi, xi = -(a_L + g e3) / |a_L + g e3|.

#include <Eigen/Core>
#include <cstdint>
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
  int line = 0;  // the reference CSV's line it was read from (0: not read from a file)
};

/// A payload trajectory through samples (at least two, strictly increasing times): position,
/// velocity and acceleration linear between samples (the jerk is the acceleration's slope),
/// the first sample held before it, the last one held at rest after it.
std::shared_ptr<Reference> MakeSampledReference(const Params& params,
                                                std::vector<TrajectorySample> samples);

/// Largest reference CSV read: an hour (the longest scenario) sampled at the 150 Hz control rate
/// with all ten columns at 12 characters is 540 000 rows of 130 bytes, 70 MB; twice that, so
/// that /dev/zero or a runaway file is refused at once instead of read for minutes.
constexpr std::uintmax_t kMaxReferenceCsvBytes = std::uintmax_t{128} << 20;

/// Smallest time step between two rows of a reference CSV. The simulator's finest clock is the
/// 1 ms physics step: rows closer than a tenth of it carry nothing any loop can see, and
/// differencing across them multiplies the file's rounding by 1 / step^2 (a 1e-300 s step turns
/// a 1 m jump into an infinite acceleration).
constexpr double kMinTrajectoryStep_s = 1e-4;

/// Fastest payload speed a reference CSV may give or imply. Full thrust (thrust-to-weight 2.5,
/// params.yaml) accelerates the vehicle sideways at most g sqrt(2.5^2 - 1) = 22.5 m/s^2; from
/// rest along the arena's longest line (its 30 m diagonal) that reaches sqrt(2 x 22.5 x 30) =
/// 37 m/s. A faster reference cannot be flown in the arena; 40 m/s is also the payload speed the
/// estimator's health check refuses (EstimatorConfig::max_payload_relative_speed_mps).
constexpr double kMaxTrajectorySpeed_mps = 40.0;

/// The range every coordinate of a reference CSV's positions must lie in (world, m). The
/// scenario loader passes the hover reference's declared range, so every reference shares one
/// position bound.
struct PositionRange {
  double min_m = 0.0;
  double max_m = 0.0;
};

/// Reads a reference CSV (at most kMaxReferenceCsvBytes, a regular file: a FIFO or device is
/// refused without being read) and parses it as ParseTrajectoryCsv does.
std::vector<TrajectorySample> LoadTrajectoryCsv(const std::string& path,
                                                const PositionRange& range);

/// Parses a reference CSV's text (`path` names it in messages): a header naming t_s, x_m, y_m,
/// z_m and optionally vx_mps, vy_mps, vz_mps and ax_mps2, ay_mps2, az_mps2 (a UTF-8 byte order
/// mark before it is skipped), then one row per sample. Missing velocities and accelerations
/// come from central differences (one-sided at the ends). Throws InputError naming the file,
/// line and column for a missing or unknown column, a short row, a value that is not a finite
/// number, a position outside `range`, times that do not increase by at least
/// kMinTrajectoryStep_s, a speed above kMaxTrajectorySpeed_mps or a derived value that is not
/// finite, or fewer than two rows.
std::vector<TrajectorySample> ParseTrajectoryCsv(const std::string& text, const std::string& path,
                                                 const PositionRange& range);

/// Checks the quadrotor reference a sampled trajectory gives (differential flatness with
/// `params`) at every sample: the payload's acceleration must stay above free fall (a_z > -g,
/// so that a taut cable can hold it and the cable's direction is defined between samples too)
/// and every value of the reference point must be finite. Throws InputError naming `file` and
/// the sample's line.
void CheckSampledReference(const Params& params, const std::vector<TrajectorySample>& samples,
                           const std::string& file);

}  // namespace hpa
