// The team controllers by name: "cooperative" (cooperative_controller.cc) and "hpa_mpc" (the
// single-vehicle HPA-MPC flying its share of the payload at its attachment point).

#include "hpa/controller/team_controller.h"

#include <cmath>
#include <stdexcept>
#include <utility>

#include "hpa/controller/cooperative_controller.h"

namespace hpa {
namespace {

// The wrapped payload reference at an attachment point, flat outputs for this cable's length.
class OffsetReference : public Reference {
 public:
  OffsetReference(std::shared_ptr<const Reference> payload_reference,
                  const Eigen::Vector3d& p_LA_W_m, double cable_length_m)
      : inner_(std::move(payload_reference)), p_LA_W_m_(p_LA_W_m), l_m_(cable_length_m) {}

  ReferencePoint At(double t_s) const override {
    ReferencePoint r = inner_->At(t_s);
    // the wrapped flat output is x_Q = x_L + l_ref u with u = n / |n|, n = a_L + g e3 (and its
    // derivatives): u = -xi, l_ref = |x_Q - x_L|, u' = (v_Q - v_L) / l_ref, u'' likewise; the
    // offset moves neither n nor its derivatives, so only the length changes
    const Eigen::Vector3d u = -r.xi_W;
    const double l_ref_m = (r.p_WQ_W - r.p_WL_W).norm();
    const Eigen::Vector3d u1 = (r.v_WQ_W - r.v_WL_W) / l_ref_m;
    const Eigen::Vector3d u2 = (r.a_WQ_W - r.a_WL_W) / l_ref_m;
    r.p_WL_W += p_LA_W_m_;
    r.p_WQ_W = r.p_WL_W + l_m_ * u;
    r.v_WQ_W = r.v_WL_W + l_m_ * u1;
    r.a_WQ_W = r.a_WL_W + l_m_ * u2;
    return r;
  }

 private:
  std::shared_ptr<const Reference> inner_;
  Eigen::Vector3d p_LA_W_m_;  // attachment offset of the level payload, world  (3)
  double l_m_;                // this vehicle's cable length
};

// The single-vehicle HPA-MPC on one vehicle of a team: its share of the payload's mass hangs at
// its attachment point; the other vehicles' cables are disturbances it does not model.
class TeamHpaMpc : public TeamController {
 public:
  TeamHpaMpc(const CooperativeTeam& team, int vehicle,
             std::shared_ptr<const Reference> payload_reference)
      : vehicle_(team.vehicles[vehicle]) {
    params_ = vehicle_.params;
    params_.payload_mass_kg = team.payload_mass_kg / static_cast<double>(team.vehicles.size());
    params_.cable_length_m = vehicle_.cable_length_m;
    ControllerConfig config;
    config.type = "hpa_mpc";
    mpc_ = MakeController(config, params_,
                          MakeOffsetReference(std::move(payload_reference), vehicle_.p_PA_P_m,
                                              vehicle_.cable_length_m));
  }

  ControlOutput Update(const TeamView& view) override {
    if (!AllFinite(view)) {
      ControlOutput out;
      out.status = ControlStatus::kNonFinite;
      out.command = LevelOutCommand(params_, view.q_WB);
      return out;
    }
    // the payload the MPC sees: this vehicle's attachment point
    const Eigen::Matrix3d r_wp = view.q_WP.normalized().toRotationMatrix();
    SystemState s;
    s.time_s = view.time_s;
    s.p_WL_W = view.p_WL_W + r_wp * vehicle_.p_PA_P_m;
    s.v_WL_W = view.v_WL_W + r_wp * view.w_P.cross(vehicle_.p_PA_P_m);
    s.p_WQ_W = view.p_WQ_W;
    s.v_WQ_W = view.v_WQ_W;
    s.q_WB = view.q_WB;
    s.w_B = view.w_B;
    taut_ = (s.p_WL_W - s.p_WQ_W).norm() >= vehicle_.cable_length_m - kSlackBand_m;
    s.mode = taut_ ? CableMode::kTaut : CableMode::kSlack;
    return mpc_->Update(s);
  }

  bool CableTaut() const override { return taut_; }
  double RateHz() const override { return mpc_->RateHz(); }

 private:
  static constexpr double kSlackBand_m = 0.01;  // shorter than the cable by this: slack
  CooperativeVehicle vehicle_;
  Params params_;  // the vehicle's, with its payload share and cable length
  std::unique_ptr<Controller> mpc_;
  bool taut_ = true;
};

// The registry: one line per team controller; TeamControllerNames and MakeTeamController read it.
using TeamControllerMaker = std::unique_ptr<TeamController> (*)(const CooperativeTeam&, int,
                                                                std::shared_ptr<const Reference>);
struct TeamControllerRegistration {
  std::string name;
  std::string description;  // one line for `hpa schema controllers`
  TeamControllerMaker make;
};
const std::vector<TeamControllerRegistration>& Registry() {
  static const std::vector<TeamControllerRegistration> registry = {
      {"cooperative",
       "RotorTM's cable-suspended cooperative controller: payload wrench, cable-force "
       "distribution, each vehicle steering its cable (100 Hz)",
       [](const CooperativeTeam& team, int vehicle,
          std::shared_ptr<const Reference> reference) -> std::unique_ptr<TeamController> {
         return std::make_unique<CooperativeController>(team, vehicle, std::move(reference));
       }},
      {"hpa_mpc",
       "the single-vehicle HPA-MPC on each vehicle, its share of the payload at its attachment "
       "point, the others disturbances (the baseline)",
       [](const CooperativeTeam& team, int vehicle,
          std::shared_ptr<const Reference> reference) -> std::unique_ptr<TeamController> {
         return std::make_unique<TeamHpaMpc>(team, vehicle, std::move(reference));
       }},
  };
  return registry;
}

}  // namespace

bool AllFinite(const TeamView& view) {
  return std::isfinite(view.time_s) && view.p_WQ_W.allFinite() && view.v_WQ_W.allFinite() &&
         view.q_WB.coeffs().allFinite() && view.w_B.allFinite() && view.p_WL_W.allFinite() &&
         view.v_WL_W.allFinite() && view.q_WP.coeffs().allFinite() && view.w_P.allFinite();
}

std::shared_ptr<const Reference> MakeOffsetReference(
    std::shared_ptr<const Reference> payload_reference, const Eigen::Vector3d& p_LA_W_m,
    double cable_length_m) {
  if (!payload_reference) throw std::invalid_argument("offset reference: null reference");
  if (!(cable_length_m > 0.0)) {
    throw std::invalid_argument("offset reference: cable length must be positive");
  }
  return std::make_shared<OffsetReference>(std::move(payload_reference), p_LA_W_m, cable_length_m);
}

std::string TeamControllerDescription(const std::string& name) {
  for (const TeamControllerRegistration& r : Registry()) {
    if (r.name == name) return r.description;
  }
  return {};
}

const std::vector<std::string>& TeamControllerNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> list;
    for (const TeamControllerRegistration& r : Registry()) list.push_back(r.name);
    return list;
  }();
  return names;
}

std::unique_ptr<TeamController> MakeTeamController(
    const std::string& type, const CooperativeTeam& team, int vehicle,
    std::shared_ptr<const Reference> payload_reference) {
  const int n = static_cast<int>(team.vehicles.size());
  if (vehicle < 0 || vehicle >= n) {
    throw std::invalid_argument("team controller: vehicle " + std::to_string(vehicle) +
                                " outside a team of " + std::to_string(n));
  }
  if (!payload_reference) throw std::invalid_argument("team controller: null reference");
  for (const TeamControllerRegistration& r : Registry()) {
    if (r.name == type) return r.make(team, vehicle, std::move(payload_reference));
  }
  std::string names;
  for (const std::string& name : TeamControllerNames()) names += (names.empty() ? "" : ", ") + name;
  throw std::invalid_argument("team controller type: expected one of " + names + ", got '" + type +
                              "'");
}

}  // namespace hpa
