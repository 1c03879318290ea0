#pragma once
// The analytic cooperative model: N quadrotors, each on its own cable, carrying one rigid-body
// payload (RotorTM's cable-suspended cooperative model; docs/cooperative.md). A point-mass
// payload is the case where every cable attaches at the payload's centre.

#include <Eigen/Core>
#include <vector>

#include "hpa/models/hybrid_model.h"
#include "hpa/models/params.h"
#include "hpa/models/state.h"

namespace hpa {

/// Most vehicles a team flies: the cooperative scenes (CooperativeSceneXml) are written for up to
/// three. The scenario reader, the events' `vehicle` key and the team's world all read this one.
constexpr int kMaxTeamVehicles = 3;

/// One vehicle of the team: the same rigid-body quadrotor as HybridModel's, on its own cable.
struct CooperativeVehicle {
  Params params;                                       // mass, inertia, rotors, gravity
  double cable_length_m = 0.5;                         // this vehicle's cable
  Eigen::Vector3d p_PA_P_m = Eigen::Vector3d::Zero();  // attachment point, payload frame (3)
};

/// The payload and the vehicles carrying it. The vehicles' params' payload mass and cable length
/// are not read (the payload's and each cable's are here); the MuJoCo scene draws the payload
/// with the first vehicle's payload_radius_m.
struct CooperativeTeam {
  double payload_mass_kg = 0.1;
  Eigen::Vector3d payload_inertia_P_kgm2{1e-4, 1e-4, 1e-4};  // diagonal, payload frame (3)
  double gravity_mps2 = 9.81;                                // on the payload
  std::vector<CooperativeVehicle> vehicles;                  // N >= 1

  /// The single vehicle of params as a team of one: cable at the payload's centre.
  static CooperativeTeam SingleVehicle(const Params& params);
};

/// Offsets in the cooperative state vector, RotorTM's layout: the payload block
/// [p_WL_W, v_WL_W, q_WP (w,x,y,z), w_P] (13), then one block per vehicle laid out as
/// StateIndex's quadrotor slice [p_WQ_W, v_WQ_W, q_WB, w_B] (13), so a vehicle block is
/// x19.segment<13>(StateIndex::kQuadPos) of the single-vehicle state.
struct CooperativeStateIndex {
  static constexpr int kPayloadPos = 0;
  static constexpr int kPayloadVel = 3;
  static constexpr int kPayloadQuat = 6;  // w, x, y, z
  static constexpr int kPayloadRate = 10;
  static constexpr int kBlockSize = 13;  // payload block and each vehicle block
  static constexpr int kVehiclePos = StateIndex::kQuadPos - StateIndex::kQuadPos;
  static constexpr int kVehicleVel = StateIndex::kQuadVel - StateIndex::kQuadPos;
  static constexpr int kVehicleQuat = StateIndex::kQuat - StateIndex::kQuadPos;
  static constexpr int kVehicleRate = StateIndex::kBodyRate - StateIndex::kQuadPos;
  /// Start of vehicle i's block.
  static constexpr int Vehicle(int i) { return kBlockSize * (i + 1); }
  /// Size of the state of n vehicles and the payload.
  static constexpr int Size(int n) { return kBlockSize * (n + 1); }
};

/// Cooperative hybrid model: a flow per combination of cable modes and the inelastic re-taut jump.
///
/// Taut cable i pulls its vehicle with T_i xi_i, xi_i = (p_A_i - p_Q_i) / |.| (vehicle to
/// attachment), and the payload with the force and moment RotorTM writes in terms of the
/// effective mass ML = m_L I + sum m_i xi_i xi_i^T and the coupling matrices C, D, E; a slack
/// cable exerts nothing. RotorTM's centripetal term l_i |xi_i x xi_dot_i|^2 is written
/// |v_perp|^2 / d + k_d v_r + k_p (d - l) (HybridModel's Baumgarte stabilisation), which equals
/// it on the constraint (d = l, v_r = 0) and holds each cable's length against drift.
class CooperativeModel {
 public:
  /// Copies the team; throws std::invalid_argument on an empty team or non-positive numbers.
  explicit CooperativeModel(CooperativeTeam team);

  /// Number of vehicles N.
  int VehicleCount() const { return static_cast<int>(team_.vehicles.size()); }
  /// Length of the state vector, 13 (N + 1).
  int StateSize() const { return CooperativeStateIndex::Size(VehicleCount()); }

  /// x_dot for x (StateSize()), u (4N rotor speeds rad/s, vehicle by vehicle), one mode per cable.
  Eigen::VectorXd Derivative(const Eigen::VectorXd& x, const Eigen::VectorXd& u,
                             const std::vector<CableMode>& modes) const;

  /// One RK4 step of dt_s with u and the modes held, every quaternion renormalised at the end.
  Eigen::VectorXd Step(const Eigen::VectorXd& x, const Eigen::VectorXd& u,
                       const std::vector<CableMode>& modes, double dt_s) const;

  /// Tension (N) of each cable under the flow: T_i for a taut cable, 0 for a slack one.
  Eigen::VectorXd CableTensionsN(const Eigen::VectorXd& x, const Eigen::VectorXd& u,
                                 const std::vector<CableMode>& modes) const;

  /// Cables at their length (d > l - taut_band_m) whose attachment moves away from the vehicle
  /// along xi faster than speed_threshold_mps: the ones a re-taut collision acts on (RotorTM's
  /// cooperative_check_inelastic).
  std::vector<bool> RetautingCables(const Eigen::VectorXd& x, double taut_band_m = 1e-3,
                                    double speed_threshold_mps = 1e-3) const;

  /// The perfectly inelastic collision of the payload with the vehicles whose cables are marked:
  /// payload velocity and rate, and each marked vehicle's velocity along its cable, such that
  /// every marked cable stops stretching, with the momentum along the cables kept (RotorTM's
  /// rigidbody_quad_inelastic_cable_collision). Positions and attitudes are unchanged.
  Eigen::VectorXd RetautCollision(const Eigen::VectorXd& x,
                                  const std::vector<bool>& colliding) const;

  /// A taut equilibrium layout: payload at p_WL_W, level, each vehicle straight above its
  /// attachment point at its cable length, all at rest.
  Eigen::VectorXd HangingState(const Eigen::Vector3d& p_WL_W) const;

  /// The cooperative state of a single-vehicle state (N = 1 teams): payload level and not rotating.
  static Eigen::VectorXd FromSingleVehicleState(const StateVector& x);

  const CooperativeTeam& team() const { return team_; }

 private:
  CooperativeTeam team_;
  std::vector<HybridModel> quadrotors_;  // vehicle i's rigid body and rotors (its slack flow)
};

}  // namespace hpa
