#include "hpa/controller/geometric_controller.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace hpa {

GeometricController::GeometricController(const Params& params,
                                         std::shared_ptr<const Reference> reference,
                                         const GeometricGains& gains)
    : params_(params), reference_(std::move(reference)), gains_(gains) {
  if (!reference_) throw std::invalid_argument("geometric controller: null reference");
}

ControlOutput GeometricController::Update(const SystemState& state) {
  const auto start = std::chrono::steady_clock::now();
  ControlOutput out;
  if (!state.AllFinite() || !std::isfinite(state.time_s)) {
    out.status = ControlStatus::kNonFinite;
    out.command = LevelOutCommand(params_, state.q_WB);
    return out;
  }
  const ReferencePoint ref = reference_->At(state.time_s);
  const Eigen::Vector3d g_e3(0, 0, params_.gravity_mps2);
  const double m = params_.quad_mass_kg;
  const double m_L = params_.payload_mass_kg;
  const bool taut = state.mode == CableMode::kTaut;

  // desired force: feedback on the quadrotor's flat output plus the feed-forward
  const double m_eff = taut ? m + m_L : m;
  Eigen::Vector3d f_ff_N = m * (ref.a_WQ_W + g_e3);
  if (taut) f_ff_N += m_L * (ref.a_WL_W + g_e3);
  const Eigen::Vector3d e_p = state.p_WQ_W - ref.p_WQ_W;
  const Eigen::Vector3d e_v = state.v_WQ_W - ref.v_WQ_W;
  Eigen::Vector3d f_des_N = f_ff_N - m_eff * (gains_.k_position_per_s2.cwiseProduct(e_p) +
                                              gains_.k_velocity_per_s.cwiseProduct(e_v));

  // keep the vertical component positive and the tilt inside the limit
  f_des_N.z() = std::max(f_des_N.z(), 0.2 * m * params_.gravity_mps2);
  const double horizontal = f_des_N.head<2>().norm();
  const double max_horizontal = f_des_N.z() * std::tan(gains_.max_tilt_rad);
  if (horizontal > max_horizontal) f_des_N.head<2>() *= max_horizontal / horizontal;

  // desired attitude: b3 along the force, yaw 0
  const Eigen::Vector3d b3 = f_des_N.normalized();
  Eigen::Vector3d b2 = b3.cross(Eigen::Vector3d::UnitX());
  if (b2.norm() < 1e-6) b2 = Eigen::Vector3d::UnitY();
  b2.normalize();
  const Eigen::Vector3d b1 = b2.cross(b3);
  Eigen::Matrix3d r_des;
  r_des << b1, b2, b3;
  out.command = AttitudeCascadeCommand(f_des_N, r_des, state.q_WB, gains_.k_attitude_per_s,
                                       gains_.max_rate_radps);
  out.status = ControlStatus::kSuccess;
  out.solve_time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return out;
}

BodyRateCommand AttitudeCascadeCommand(const Eigen::Vector3d& force_W_N,
                                       const Eigen::Matrix3d& r_des, const Eigen::Quaterniond& q_WB,
                                       const Eigen::Vector3d& k_attitude_per_s,
                                       double max_rate_radps) {
  const Eigen::Matrix3d r = q_WB.normalized().toRotationMatrix();
  const Eigen::Matrix3d e = 0.5 * (r_des.transpose() * r - r.transpose() * r_des);
  const Eigen::Vector3d e_r(e(2, 1), e(0, 2), e(1, 0));
  BodyRateCommand command;
  command.w_B_radps =
      (-k_attitude_per_s.cwiseProduct(e_r)).cwiseMax(-max_rate_radps).cwiseMin(max_rate_radps);
  command.thrust_N = std::max(0.0, force_W_N.dot(r.col(2)));
  return command;
}

std::unique_ptr<Controller> MakeGeometricController(const ControllerConfig& config,
                                                    const Params& params,
                                                    std::shared_ptr<const Reference> reference) {
  return std::make_unique<GeometricController>(params, std::move(reference));
}

}  // namespace hpa
