#pragma once
// Cable EKF of the paper's section V: state (xi, xi_dot) in the world frame, process model driven
// by the commanded thrust and the attitude, measurement of the payload position in the body frame.

#include <Eigen/Core>

#include "hpa/estimator/filter_status.h"
#include "hpa/models/params.h"
#include "hpa/models/ring_queue.h"

namespace hpa {

/// Noise model and tuning of the cable EKF (1-sigma values).
struct CableEkfConfig {
  double xi_noise_per_sqrts = 1e-3;       // process noise density on xi (model slip)
  double xi_ddot_noise_per_s15 = 1.0;     // process noise density on xi_ddot (thrust lag,
                                          // attitude error, unmodelled payload drag)
  double initial_xi_std = 0.3;            // per axis, unit-vector components
  double initial_xi_dot_std_per_s = 1.0;  // per axis
  double history_s = 0.5;                 // how late a detection may arrive
  // longest step of one RK4 and linearised covariance step: a longer gap between inputs is
  // taken in equal sub-steps (twice the 500 Hz IMU period; the |xi_dot|^2 term makes one long
  // step unstable at swing rates)
  double max_step_s = 0.004;
  // detection gate: NIS over 30 rejects (3 dof: the 99.99% quantile is 21); the fourth
  // rejection in a row is accepted anyway (e.g. after an unmodelled jerk of the cable)
  InnovationGate gate = {30.0, 3};
};

/// Cable state: unit vector from the quadrotor to the payload and its rate (world frame).
using CableVector = Eigen::Matrix<double, 6, 1>;  // [xi_W, xi_dot_W]
using CableMatrix = Eigen::Matrix<double, 6, 6>;

/// EKF on (xi, xi_dot) with xi_ddot = 1/(m l) xi x (xi x f R e3) - |xi_dot|^2 xi; after every
/// step xi is renormalised to the unit sphere and xi_dot projected onto its tangent plane.
class CableEkf {
 public:
  /// Starts at (xi_W, xi_dot_W) at time_s with the configured initial covariance.
  CableEkf(const Params& params, const CableEkfConfig& config, const Eigen::Vector3d& xi_W,
           const Eigen::Vector3d& xi_dot_W, double time_s);

  /// Propagates to time_s under collective thrust thrust_N and attitude R_WB (both held).
  FilterStatus Predict(double time_s, double thrust_N, const Eigen::Matrix3d& R_WB);

  /// Fuses p_BL_B (payload position in the body frame, measured at capture_time_s with body
  /// attitude R_WB then) with covariance cov_B_m2: rewinds to the capture time, updates with
  /// h = R^T l xi, re-propagates the stored inputs.
  FilterStatus Update(double capture_time_s, const Eigen::Vector3d& p_BL_B,
                      const Eigen::Matrix3d& R_WB, const Eigen::Matrix3d& cov_B_m2);

  /// Fuses the paper's velocity row, Z_2 = l (R^T xi_dot - w_B x R^T xi) = v_BL_B (the rate of
  /// the body-frame payload position as the body sees it), at capture_time_s
  /// (e.g. a finite difference of two detections, at the middle of their gap) with covariance
  /// cov_B (3x3).
  FilterStatus UpdateVelocity(double capture_time_s, const Eigen::Vector3d& v_BL_B,
                              const Eigen::Matrix3d& R_WB, const Eigen::Vector3d& w_B_radps,
                              const Eigen::Matrix3d& cov_B);

  /// Restarts at (xi_W, xi_dot_W) with covariance `covariance` (e.g. at a slack-to-taut switch).
  void Reset(double time_s, const Eigen::Vector3d& xi_W, const Eigen::Vector3d& xi_dot_W,
             const CableMatrix& covariance);

  Eigen::Vector3d xi_W() const { return x_.head<3>(); }
  Eigen::Vector3d xi_dot_W() const { return x_.tail<3>(); }
  const CableMatrix& covariance() const { return covariance_; }
  double time_s() const { return time_s_; }
  /// Counts of refused predictions and of accepted, rejected and forced updates.
  const FilterCounts& counts() const { return counts_; }
  /// Detection gate rejections in a row so far (the gate forces an accept at its maximum).
  int consecutive_rejections() const { return consecutive_rejections_; }
  /// The configuration the filter runs with.
  const CableEkfConfig& config() const { return config_; }

  /// Continuous-time derivative of [xi, xi_dot] (the paper's process model).
  static CableVector Derivative(const CableVector& x, const Eigen::Vector3d& force_W_N,
                                double quad_mass_kg, double cable_length_m);

 private:
  struct Entry {
    double time_s;
    CableVector x;
    CableMatrix covariance;
    double thrust_N;  // input that brought the filter to this entry
    Eigen::Matrix3d R_WB;
  };
  // Counts a refused step and returns its status.
  FilterStatus Refused(FilterStatus status);
  void Propagate(double dt_s, double thrust_N, const Eigen::Matrix3d& R_WB, CableVector* x,
                 CableMatrix* covariance) const;
  // Rewinds to the capture time, applies `fuse` (x, covariance -> status) there and re-propagates
  // the stored inputs; kTooOld when the capture time is before the history.
  template <typename Fuse>
  FilterStatus FuseAtCaptureTime(double capture_time_s, const Fuse& fuse);

  Params params_;
  CableEkfConfig config_;
  double time_s_;
  CableVector x_;
  CableMatrix covariance_;
  RingQueue<Entry> history_;        // one entry per prediction, oldest first
  int consecutive_rejections_ = 0;  // gate rejections in a row
  FilterCounts counts_;
};

}  // namespace hpa
