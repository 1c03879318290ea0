#include "hpa/autopilot/px4_rate_controller.h"

#include <algorithm>
#include <cmath>

#include "hpa/models/rotor_model.h"

namespace hpa {

const ParamTable<Px4RateParams>& Px4RateParamTable() {
  using P = Px4RateParams;
  static const ParamTable<P> t{
      "rate_loop",
      "PX4's multicopter rate controller and control allocation (flight-code parameters)",
      {{"rate_hz", "Hz", 50.0, 1000.0,
        "loop and gyro rate (PX4 runs the loop on each gyro sample); divides 1000 Hz", &P::rate_hz},
       {"p", "1/(rad/s)", 0.0, 0.6, "MC_ROLLRATE_P, MC_PITCHRATE_P, MC_YAWRATE_P", &P::p, "", 3,
        {{{0.01, 0.5}, {0.01, 0.6}, {0.0, 0.6}}}},
       {"i", "1/rad", 0.0, 5.0, "MC_*RATE_I", &P::i},
       {"d", "1/(rad/s^2)", 0.0, 0.05, "MC_ROLLRATE_D, MC_PITCHRATE_D, MC_YAWRATE_D", &P::d, "", 3,
        {{{0.0, 0.01}, {0.0, 0.05}, {0.0, 0.05}}}},
       {"k", "-", 0.01, 5.0, "MC_*RATE_K: scales P, I and D", &P::k},
       {"integrator_limit", "-", 0.0, 1.0, "MC_RR_INT_LIM, MC_PR_INT_LIM, MC_YR_INT_LIM",
        &P::integrator_limit},
       {"gyro_cutoff_hz", "Hz", 0.0, 1000.0, "IMU_GYRO_CUTOFF: Butterworth on the gyro",
        &P::gyro_cutoff_hz},
       {"dgyro_cutoff_hz", "Hz", 0.0, 1000.0, "IMU_DGYRO_CUTOFF: Butterworth on d(gyro)/dt",
        &P::dgyro_cutoff_hz},
       {"yaw_torque_cutoff_hz", "Hz", 0.0, 10.0, "MC_YAW_TQ_CUTOFF: low-pass on the yaw torque",
        &P::yaw_torque_cutoff_hz},
       {"yaw_headroom", "-", 0.0, 1.0,
        "mixYaw: yaw may push actuators this fraction past their maximum (a constant in PX4's "
        "ControlAllocationSequentialDesaturation, not a parameter)",
        &P::yaw_headroom}}};
  return t;
}
namespace {

// Rotor thrust range: f = f_min + u (f_max - f_min).
double RotorThrustMinN(const Params& p) {
  return p.k_f_N_per_radps2 * p.motor_speed_min_radps * p.motor_speed_min_radps;
}
double RotorThrustRangeN(const Params& p) {
  return p.k_f_N_per_radps2 * p.motor_speed_max_radps * p.motor_speed_max_radps -
         RotorThrustMinN(p);
}

// PX4's normalised mix: columns roll, pitch, yaw (actuator change per unit normalised torque).
Eigen::Matrix<double, 4, 3> NormalisedMix(const Params& params, const Px4TorqueScale& scale) {
  // the pseudo-inverse of the effectiveness u -> (M, f above 4 f_min) is A^-1 / (f_max - f_min)
  const Eigen::Matrix4d pinv = AllocationMatrix(params).inverse() / RotorThrustRangeN(params);
  Eigen::Matrix<double, 4, 3> mix;
  for (int axis = 0; axis < 3; ++axis) mix.col(axis) = pinv.col(1 + axis) * scale.torque_Nm(axis);
  return mix;
}

// PX4's computeDesaturationGain: the gain k on `vec` that brings the most saturated actuators back
// to their bounds (k_min + k_max over the violated bounds; entries below 0.2 are not used).
double DesaturationGain(const Eigen::Vector4d& vec, const Eigen::Vector4d& u, double u_max) {
  double k_min = 0.0, k_max = 0.0;
  for (int i = 0; i < 4; ++i) {
    if (std::abs(vec(i)) < 0.2) continue;
    if (u(i) < 0.0) {
      const double k = (0.0 - u(i)) / vec(i);
      k_min = std::min(k_min, k);
      k_max = std::max(k_max, k);
    }
    if (u(i) > u_max) {
      const double k = (u_max - u(i)) / vec(i);
      k_min = std::min(k_min, k);
      k_max = std::max(k_max, k);
    }
  }
  return k_min + k_max;
}

// PX4's desaturateActuators: a full step then half a step along `vec`. lower_only: only a
// negative gain is applied (PX4's increase_only on its thrust axis, which points down in FRD;
// here the thrust column is +1, so the same rule reads "thrust is only lowered").
void Desaturate(const Eigen::Vector4d& vec, bool lower_only, double u_max, Eigen::Vector4d* u) {
  double gain = DesaturationGain(vec, *u, u_max);
  if (lower_only && gain > 0.0) return;
  *u += gain * vec;
  gain = 0.5 * DesaturationGain(vec, *u, u_max);
  *u += gain * vec;
}

}  // namespace

Px4TorqueScale Px4RateController::TorqueScale(const Params& params) {
  const Eigen::Matrix4d pinv = AllocationMatrix(params).inverse() / RotorThrustRangeN(params);
  Px4TorqueScale s;
  // roll and pitch: one scale, |col|^2 = n / 2 over the rotors that act on the axis
  double rp_scale = 0.0;
  for (int axis = 1; axis <= 2; ++axis) {
    const int nonzero = static_cast<int>((pinv.col(axis).array().abs() > 1e-9).count());
    if (nonzero > 0) {
      rp_scale = std::max(rp_scale, std::sqrt(pinv.col(axis).squaredNorm() / (nonzero / 2.0)));
    }
  }
  s.torque_Nm(0) = s.torque_Nm(1) = 1.0 / rp_scale;
  // yaw: largest entry 1; thrust: mean absolute entry 1
  s.torque_Nm(2) = 1.0 / pinv.col(3).maxCoeff();
  s.thrust_N = 1.0 / pinv.col(0).cwiseAbs().mean();
  return s;
}

Px4Allocation Px4RateController::AllocateAirmodeDisabled(const Params& params,
                                                         const Eigen::Vector3d& torque,
                                                         double thrust, double yaw_headroom) {
  const Px4TorqueScale scale = TorqueScale(params);
  const Eigen::Matrix<double, 4, 3> mix = NormalisedMix(params, scale);
  const Eigen::Vector4d thrust_vec = Eigen::Vector4d::Ones();

  // roll, pitch and thrust; thrust only lowered, then roll and pitch scaled
  Eigen::Vector4d u = mix.col(0) * torque(0) + mix.col(1) * torque(1) + thrust_vec * thrust;
  Desaturate(thrust_vec, true, 1.0, &u);
  Desaturate(mix.col(0), false, 1.0, &u);
  Desaturate(mix.col(1), false, 1.0, &u);

  // yaw last: scaled to fit with headroom above the maximum, then thrust lowered again
  u += mix.col(2) * torque(2);
  Desaturate(mix.col(2), false, 1.0 + yaw_headroom, &u);
  Desaturate(thrust_vec, true, 1.0, &u);
  u = u.cwiseMax(0.0).cwiseMin(1.0);

  // what the clipped actuators give, normalised
  Px4Allocation a;
  a.u = u;
  const double f_min = RotorThrustMinN(params), df = RotorThrustRangeN(params);
  const Eigen::Vector4d f = Eigen::Vector4d::Constant(f_min) + df * u;
  const Eigen::Vector4d wrench = AllocationMatrix(params) * f;
  a.torque = wrench.tail<3>().cwiseQuotient(scale.torque_Nm);
  a.thrust = (wrench(0) - 4.0 * f_min) / scale.thrust_N;
  return a;
}

InputVector Px4RateController::RotorSpeeds(const Params& params, const Eigen::Vector4d& u) {
  const double f_min = RotorThrustMinN(params), df = RotorThrustRangeN(params);
  InputVector w;
  for (int i = 0; i < 4; ++i) {
    const double f = f_min + df * std::clamp(u(i), 0.0, 1.0);
    // the clamp only removes rounding at the bounds
    w(i) = std::clamp(std::sqrt(f / params.k_f_N_per_radps2), params.motor_speed_min_radps,
                      params.motor_speed_max_radps);
  }
  return w;
}

Px4RateController::Px4RateController(const Params& params, const Px4RateParams& px4)
    : params_(params),
      px4_(px4),
      scale_(TorqueScale(params)),
      gyro_filter_(px4.rate_hz, px4.gyro_cutoff_hz),
      dgyro_filter_(px4.rate_hz, px4.dgyro_cutoff_hz) {}

void Px4RateController::Reset() {
  gyro_filter_.Clear();
  dgyro_filter_.Clear();
  gyro_prev_radps_.setZero();
  has_prev_ = false;
  integral_.setZero();
  yaw_torque_filtered_ = 0.0;
  sat_pos_.setConstant(false);
  sat_neg_.setConstant(false);
}

InputVector Px4RateController::Update(const BodyRateCommand& cmd,
                                      const Eigen::Vector3d& gyro_B_radps) {
  status_ = Px4RateStatus();
  const double dt_s = 1.0 / px4_.rate_hz;
  const double f_min_total_N = 4.0 * RotorThrustMinN(params_);
  const bool valid =
      cmd.w_B_radps.allFinite() && std::isfinite(cmd.thrust_N) && gyro_B_radps.allFinite();
  if (!valid) {
    // safe output: hover thrust, zero torque, loop memory cleared
    Reset();
    status_.input_valid = false;
    const double hover = (params_.HoverThrustN() - f_min_total_N) / scale_.thrust_N;
    const Px4Allocation a =
        AllocateAirmodeDisabled(params_, Eigen::Vector3d::Zero(), hover, px4_.yaw_headroom);
    status_.thrust_sp = hover;
    status_.thrust_allocated = a.thrust;
    status_.thrust_allocated_N = f_min_total_N + a.thrust * scale_.thrust_N;
    return RotorSpeeds(params_, a.u);
  }

  // gyro: low-passed rate; derivative of the raw rate, low-passed on its own (PX4's
  // VehicleAngularVelocity differentiates before the rate's low-pass)
  const Eigen::Vector3d rate = gyro_filter_.Apply(gyro_B_radps);
  const Eigen::Vector3d accel_raw = has_prev_
                                        ? Eigen::Vector3d((gyro_B_radps - gyro_prev_radps_) / dt_s)
                                        : Eigen::Vector3d::Zero();
  gyro_prev_radps_ = gyro_B_radps;
  has_prev_ = true;
  const Eigen::Vector3d accel = dgyro_filter_.Apply(accel_raw);

  // PID in normalised torque, D on the measurement (RateControl::update)
  const Eigen::Vector3d p = px4_.k.cwiseProduct(px4_.p);
  const Eigen::Vector3d i_gain = px4_.k.cwiseProduct(px4_.i);
  const Eigen::Vector3d d = px4_.k.cwiseProduct(px4_.d);
  const Eigen::Vector3d error = cmd.w_B_radps - rate;
  Eigen::Vector3d torque = p.cwiseProduct(error) + integral_ - d.cwiseProduct(accel);

  // integrator (RateControl::updateIntegral) with the saturation of the last allocation: no
  // growth in a saturated direction, less gain for large errors, clamped to its limit
  for (int axis = 0; axis < 3; ++axis) {
    double e = error(axis);
    if (sat_pos_(axis)) e = std::min(e, 0.0);
    if (sat_neg_(axis)) e = std::max(e, 0.0);
    const double i_factor_base = e / (400.0 * M_PI / 180.0);
    const double i_factor = std::max(0.0, 1.0 - i_factor_base * i_factor_base);
    const double next = integral_(axis) + i_factor * i_gain(axis) * e * dt_s;
    if (std::isfinite(next)) {
      integral_(axis) = std::clamp(next, -px4_.integrator_limit(axis), px4_.integrator_limit(axis));
    }
  }

  // yaw torque low-pass (MC_YAW_TQ_CUTOFF; AlphaFilter: alpha = dt / (dt + 1 / (2 pi fc)))
  if (px4_.yaw_torque_cutoff_hz > 0.0) {
    const double alpha = dt_s / (dt_s + 1.0 / (2.0 * M_PI * px4_.yaw_torque_cutoff_hz));
    yaw_torque_filtered_ += alpha * (torque(2) - yaw_torque_filtered_);
    torque(2) = yaw_torque_filtered_;
  }

  // allocation; its shortfall sets the saturation flags the next integrator step reads
  const double thrust = (cmd.thrust_N - f_min_total_N) / scale_.thrust_N;
  const Px4Allocation a = AllocateAirmodeDisabled(params_, torque, thrust, px4_.yaw_headroom);
  const Eigen::Vector3d unallocated = torque - a.torque;
  sat_pos_.setConstant(false);
  sat_neg_.setConstant(false);
  if (unallocated.squaredNorm() >= 1e-6) {  // PX4: torque_setpoint_achieved otherwise
    for (int axis = 0; axis < 3; ++axis) {
      const double eps = 1.1920929e-07;  // FLT_EPSILON
      if (unallocated(axis) > eps) sat_pos_(axis) = true;
      if (unallocated(axis) < -eps) sat_neg_(axis) = true;
    }
  }

  status_.torque_sp = torque;
  status_.torque_allocated = a.torque;
  status_.thrust_sp = thrust;
  status_.thrust_allocated = a.thrust;
  status_.thrust_allocated_N = f_min_total_N + a.thrust * scale_.thrust_N;
  status_.saturated = thrust - a.thrust > 1e-6 || unallocated.squaredNorm() >= 1e-6;
  status_.integral = integral_;
  status_.saturated_positive = sat_pos_;
  status_.saturated_negative = sat_neg_;
  return RotorSpeeds(params_, a.u);
}

}  // namespace hpa
