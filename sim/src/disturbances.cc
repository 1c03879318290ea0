// Disturbances: scripted forces and impulses, velocity changes, wind, gusts and drag on the bodies
// of the world that binds it.

#include "hpa/sim/disturbances.h"

#include <mujoco/mujoco.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "hpa/sim/world.h"

namespace hpa::sim {

namespace {

constexpr double kPhysicsDt_s = World::kPhysicsDt_s;  // the step the durations count in

}  // namespace

Disturbances::Disturbances(const DisturbancesBinding& binding, const WindProfile& wind,
                           double physics_hz, uint64_t wind_seed)
    : b_(binding),
      wind_(std::make_unique<WindModel>(wind, physics_hz, wind_seed)),
      aero_vehicle_W_N_(binding.vehicles.size(), Eigen::Vector3d::Zero()) {}

int Disturbances::BodyId(int index, const char* caller) const {
  if (index < -1 || index >= static_cast<int>(b_.vehicles.size())) {
    throw std::out_of_range(std::string(caller) + ": no body " + std::to_string(index));
  }
  return index < 0 ? b_.payload_body : b_.vehicles[static_cast<size_t>(index)].body;
}

const Eigen::Vector3d& Disturbances::aero_vehicle_W_N(int vehicle) const {
  if (vehicle < 0 || vehicle >= static_cast<int>(aero_vehicle_W_N_.size())) {
    throw std::out_of_range("Disturbances::aero_vehicle_W_N: no vehicle " +
                            std::to_string(vehicle));
  }
  return aero_vehicle_W_N_[static_cast<size_t>(vehicle)];
}

Eigen::Vector3d Disturbances::Wind_W_mps() const { return wind_->Wind_W_mps(*b_.step); }

void Disturbances::SetWindVelocity(const Eigen::Vector3d& velocity_W_mps, double duration_s) {
  if (!velocity_W_mps.allFinite() || !std::isfinite(duration_s)) {
    throw std::invalid_argument("World::SetWindVelocity: non-finite velocity or duration");
  }
  wind_->SetEvent(velocity_W_mps, *b_.step, std::llround(duration_s / kPhysicsDt_s));
}

void Disturbances::ApplyAerodynamics() {
  const AeroProfile& aero = *b_.aero;
  if (!aero.enabled && !wind_->gusty()) return;  // no air
  const mjtNum* qpos = b_.data->qpos;
  const mjtNum* qvel = b_.data->qvel;
  if (wind_->gusty()) {
    wind_->StepGust(Eigen::Map<const Eigen::Vector3d>(qvel + b_.vehicles.front().dof));
  }
  if (!aero.enabled) return;
  const Eigen::Vector3d wind_W = Wind_W_mps();
  mjtNum* xfrc = b_.data->xfrc_applied;
  for (size_t v = 0; v < b_.vehicles.size(); ++v) {
    const DisturbedVehicle& vehicle = b_.vehicles[v];
    const Eigen::Quaterniond q_WB(qpos[vehicle.qpos + 3], qpos[vehicle.qpos + 4],
                                  qpos[vehicle.qpos + 5], qpos[vehicle.qpos + 6]);
    const Eigen::Vector3d v_WQ_W = Eigen::Map<const Eigen::Vector3d>(qvel + vehicle.dof);
    const Eigen::Matrix3d R_WB = q_WB.normalized().toRotationMatrix();
    const Eigen::Vector3d air_B = R_WB.transpose() * (v_WQ_W - wind_W);  // airspeed, body  (3)

    // rotor drag: linear in the airspeed in the rotor plane (Faessler et al., RA-L 2018)
    Eigen::Vector3d f_B(-aero.rotor_drag_x_Nspm * air_B.x(), -aero.rotor_drag_y_Nspm * air_B.y(),
                        0);
    // body drag: quadratic, -0.5 rho |v| diag(Cd_i A_i) v over the box's faces
    const Eigen::Vector3d& h = vehicle.params->body_half_size_m;
    const Eigen::Vector3d cd_area_B_m2(aero.body_drag_coefficient_xy * 4 * h.y() * h.z(),
                                       aero.body_drag_coefficient_xy * 4 * h.x() * h.z(),
                                       aero.body_drag_coefficient_z * 4 * h.x() * h.y());
    f_B -= 0.5 * aero.air_density_kgpm3 * air_B.norm() * cd_area_B_m2.cwiseProduct(air_B);
    aero_vehicle_W_N_[v] = R_WB * f_B;
    for (int i = 0; i < 3; ++i) xfrc[6 * vehicle.body + i] += aero_vehicle_W_N_[v](i);
  }
  // payload drag: a sphere
  const Eigen::Vector3d air_L_W = Eigen::Map<const Eigen::Vector3d>(qvel + b_.payload_dof) - wind_W;
  const double r = *b_.payload_radius_m;
  aero_payload_W_N_ = -0.5 * aero.air_density_kgpm3 * aero.payload_drag_coefficient * M_PI * r * r *
                      air_L_W.norm() * air_L_W;
  for (int i = 0; i < 3; ++i) xfrc[6 * b_.payload_body + i] += aero_payload_W_N_(i);
}

void Disturbances::Apply() {
  mju_zero(b_.data->xfrc_applied, 6 * b_.model->nbody);
  ApplyAerodynamics();
  const int64_t step = *b_.step;
  for (const TimedForce& f : forces_) {
    if (step >= f.end_step) continue;
    const int body = BodyId(f.body, "Disturbances::Apply");
    for (int i = 0; i < 3; ++i) b_.data->xfrc_applied[6 * body + i] += f.force_W_N(i);
  }
  forces_.erase(std::remove_if(forces_.begin(), forces_.end(),
                               [step](const TimedForce& f) { return step + 1 >= f.end_step; }),
                forces_.end());
}

void Disturbances::ApplyImpulse(BodyRef body, const Eigen::Vector3d& impulse_W_Ns,
                                double duration_s) {
  BodyId(body.index, "World::ApplyImpulse");
  if (!impulse_W_Ns.allFinite() || !std::isfinite(duration_s)) {
    throw std::invalid_argument("World::ApplyImpulse: non-finite impulse or duration");
  }
  const int64_t steps = std::max<int64_t>(1, std::llround(duration_s / kPhysicsDt_s));
  forces_.push_back(
      {body.index, impulse_W_Ns / (static_cast<double>(steps) * kPhysicsDt_s), *b_.step + steps});
}

void Disturbances::AddVelocity(BodyRef body, const Eigen::Vector3d& dv_W_mps) {
  BodyId(body.index, "World::AddVelocity");
  if (!dv_W_mps.allFinite()) throw std::invalid_argument("World::AddVelocity: non-finite dv");
  // a free joint's first three velocity coordinates are its linear velocity in the world frame
  const int dof =
      body.index < 0 ? b_.payload_dof : b_.vehicles[static_cast<size_t>(body.index)].dof;
  for (int i = 0; i < 3; ++i) b_.data->qvel[dof + i] += dv_W_mps(i);
}

void Disturbances::SetWind(const Eigen::Vector3d& force_W_N, double duration_s) {
  if (!force_W_N.allFinite() || !std::isfinite(duration_s)) {
    throw std::invalid_argument("World::SetWind: non-finite force or duration");
  }
  const int64_t steps = std::max<int64_t>(0, std::llround(duration_s / kPhysicsDt_s));
  for (size_t v = 0; v < b_.vehicles.size(); ++v) {
    forces_.push_back({static_cast<int>(v), force_W_N, *b_.step + steps});
  }
}

}  // namespace hpa::sim
