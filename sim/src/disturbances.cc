// Disturbances: scripted forces and impulses, velocity changes, wind, gusts and drag.

#include "hpa/sim/disturbances.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hpa/models/seed_streams.h"
#include "hpa/sim/world.h"

namespace hpa::sim {

Disturbances::Disturbances(World& world, const WorldConfig& config)
    : w_(world),
      wind_(std::make_unique<WindModel>(config.profile.wind, config.rates.physics_hz,
                                        DeriveSeed(config.seed, SeedStream::kWind))) {}

Eigen::Vector3d Disturbances::Wind_W_mps() const { return wind_->Wind_W_mps(w_.step_); }

void Disturbances::SetWindVelocity(const Eigen::Vector3d& velocity_W_mps, double duration_s) {
  if (!velocity_W_mps.allFinite() || !std::isfinite(duration_s)) {
    throw std::invalid_argument("World::SetWindVelocity: non-finite velocity or duration");
  }
  wind_->SetEvent(velocity_W_mps, w_.step_, std::llround(duration_s / World::kPhysicsDt_s));
}

void Disturbances::ApplyAerodynamics() {
  if (!w_.config_.profile.aero.enabled && !wind_->gusty()) return;  // no air
  const Truth truth = w_.GetTruth();
  const SystemState& s = truth.state;
  if (wind_->gusty()) wind_->StepGust(s.v_WQ_W);
  const AeroProfile& aero = w_.config_.profile.aero;
  if (!aero.enabled) return;
  const Eigen::Vector3d wind_W = Wind_W_mps();
  const Eigen::Matrix3d R_WB = s.q_WB.normalized().toRotationMatrix();
  const Eigen::Vector3d air_B = R_WB.transpose() * (s.v_WQ_W - wind_W);  // airspeed, body  (3)

  // rotor drag: linear in the airspeed in the rotor plane (Faessler et al., RA-L 2018)
  Eigen::Vector3d f_B(-aero.rotor_drag_x_Nspm * air_B.x(), -aero.rotor_drag_y_Nspm * air_B.y(), 0);
  // body drag: quadratic, -0.5 rho |v| diag(Cd_i A_i) v over the box's faces
  const Eigen::Vector3d& h = w_.world_params_.body_half_size_m;
  const Eigen::Vector3d cd_area_B_m2(aero.body_drag_coefficient_xy * 4 * h.y() * h.z(),
                                     aero.body_drag_coefficient_xy * 4 * h.x() * h.z(),
                                     aero.body_drag_coefficient_z * 4 * h.x() * h.y());
  f_B -= 0.5 * aero.air_density_kgpm3 * air_B.norm() * cd_area_B_m2.cwiseProduct(air_B);
  aero_quad_W_N_ = R_WB * f_B;
  // payload drag: a sphere
  const Eigen::Vector3d air_L_W = s.v_WL_W - wind_W;
  const double r = w_.world_params_.payload_radius_m;
  aero_payload_W_N_ = -0.5 * aero.air_density_kgpm3 * aero.payload_drag_coefficient * M_PI * r * r *
                      air_L_W.norm() * air_L_W;
  for (int i = 0; i < 3; ++i) {
    w_.data_->xfrc_applied[6 * w_.ids_.quad_body + i] += aero_quad_W_N_(i);
    w_.data_->xfrc_applied[6 * w_.ids_.payload_body + i] += aero_payload_W_N_(i);
  }
}

void Disturbances::Apply() {
  mju_zero(w_.data_->xfrc_applied, 6 * w_.model_->nbody);
  ApplyAerodynamics();
  for (const TimedForce& f : forces_) {
    if (w_.step_ >= f.end_step) continue;
    const int body = f.body == Body::kQuadrotor ? w_.ids_.quad_body : w_.ids_.payload_body;
    for (int i = 0; i < 3; ++i) w_.data_->xfrc_applied[6 * body + i] += f.force_W_N(i);
  }
  forces_.erase(std::remove_if(forces_.begin(), forces_.end(),
                               [this](const TimedForce& f) { return w_.step_ + 1 >= f.end_step; }),
                forces_.end());
}

void Disturbances::ApplyImpulse(Body body, const Eigen::Vector3d& impulse_W_Ns, double duration_s) {
  if (!impulse_W_Ns.allFinite() || !std::isfinite(duration_s)) {
    throw std::invalid_argument("World::ApplyImpulse: non-finite impulse or duration");
  }
  const int64_t steps = std::max<int64_t>(1, std::llround(duration_s / World::kPhysicsDt_s));
  forces_.push_back({body, impulse_W_Ns / (steps * World::kPhysicsDt_s), w_.step_ + steps});
}

void Disturbances::AddVelocity(Body body, const Eigen::Vector3d& dv_W_mps) {
  if (!dv_W_mps.allFinite()) throw std::invalid_argument("World::AddVelocity: non-finite dv");
  // a free joint's first three velocity coordinates are its linear velocity in the world frame
  const int dof = body == Body::kQuadrotor ? w_.ids_.quad_jnt_dof : w_.ids_.payload_jnt_dof;
  for (int i = 0; i < 3; ++i) w_.data_->qvel[dof + i] += dv_W_mps(i);
}

void Disturbances::SetWind(const Eigen::Vector3d& force_W_N, double duration_s) {
  if (!force_W_N.allFinite() || !std::isfinite(duration_s)) {
    throw std::invalid_argument("World::SetWind: non-finite force or duration");
  }
  const int64_t steps = std::max<int64_t>(0, std::llround(duration_s / World::kPhysicsDt_s));
  forces_.push_back({Body::kQuadrotor, force_W_N, w_.step_ + steps});
}

}  // namespace hpa::sim
