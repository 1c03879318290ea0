#pragma once
// One vehicle's flight code in a team carrying one payload (docs/cooperative.md): what it knows
// at a control step, and the controllers that fly it. Each vehicle runs its own instance and sees
// only its own state and the payload's, as the team's messages delivered them. Flight code: no
// MuJoCo, no GL.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "hpa/controller/controller.h"
#include "hpa/controller/reference.h"
#include "hpa/models/cooperative_model.h"

namespace hpa {

/// What vehicle `vehicle`'s flight code knows at a control step.
struct TeamView {
  double time_s = 0.0;
  // its own state (motion capture, body rate from its gyro)
  Eigen::Vector3d p_WQ_W = Eigen::Vector3d::Zero();          // position, world (3)
  Eigen::Vector3d v_WQ_W = Eigen::Vector3d::Zero();          // velocity, world (3)
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();  // attitude
  Eigen::Vector3d w_B = Eigen::Vector3d::Zero();             // body rate, body frame (3)
  // the payload's (motion capture)
  Eigen::Vector3d p_WL_W = Eigen::Vector3d::Zero();          // position, world (3)
  Eigen::Vector3d v_WL_W = Eigen::Vector3d::Zero();          // velocity, world (3)
  Eigen::Quaterniond q_WP = Eigen::Quaterniond::Identity();  // attitude
  Eigen::Vector3d w_P = Eigen::Vector3d::Zero();             // body rate, payload frame (3)
};

/// One vehicle's controller in a team: a body-rate and thrust command for its autopilot.
class TeamController {
 public:
  virtual ~TeamController() = default;
  /// The command from what the vehicle knows now; always safe to fly (a non-finite view gives
  /// LevelOutCommand with status kNonFinite).
  virtual ControlOutput Update(const TeamView& view) = 0;
  /// Whether the controller sees vehicle's cable taut now (its own reading of the view).
  virtual bool CableTaut() const = 0;
  /// Rate the runner calls Update at (Hz).
  virtual double RateHz() const = 0;
};

/// The team controllers a scenario may name: "cooperative" (RotorTM's cable-suspended
/// cooperative controller) and "hpa_mpc" (the single-vehicle HPA-MPC on each vehicle, carrying
/// its share of the payload at its attachment point, the others treated as disturbances).
const std::vector<std::string>& TeamControllerNames();

/// One line saying what the team controller `name` is ("" for an unknown name).
std::string TeamControllerDescription(const std::string& name);

/// Vehicle `vehicle`'s controller of type `type` for `team`, tracking the payload reference
/// `payload_reference` (the payload's centre; the payload held level, yaw 0). Throws
/// std::invalid_argument for an unknown type or vehicle.
std::unique_ptr<TeamController> MakeTeamController(
    const std::string& type, const CooperativeTeam& team, int vehicle,
    std::shared_ptr<const Reference> payload_reference);

/// True when every number of the view is finite.
bool AllFinite(const TeamView& view);

/// A payload reference moved by the constant world offset p_LA_W_m (an attachment point of the
/// level payload), with its flat quadrotor output rebuilt for a cable of cable_length_m: the
/// cable direction of a level, non-rotating payload is the same at every attachment point, so
/// the wrapped reference's own unit vector and its derivatives are rescaled (no numerical
/// differentiation). Throws std::invalid_argument for a null reference or a non-positive length.
std::shared_ptr<const Reference> MakeOffsetReference(
    std::shared_ptr<const Reference> payload_reference, const Eigen::Vector3d& p_LA_W_m,
    double cable_length_m);

}  // namespace hpa
