// The PD hover controller of pd_hover.h: position and velocity PD to a thrust vector, attitude
// error to body rates.
#include "pd_hover.h"

#include <algorithm>
#include <memory>
#include <utility>

#include "hpa/models/params.h"

namespace {

// Position PD (2 rad/s, damping 0.75) to a thrust vector for quadrotor + payload, its direction
// tracked by a 6 1/s attitude loop; zero yaw.
class PdHover : public hpa::Controller {
 public:
  PdHover(const hpa::Params& params, std::shared_ptr<const hpa::Reference> reference)
      : params_(params), reference_(std::move(reference)) {}

  hpa::ControlOutput Update(const hpa::SystemState& s) override {
    const hpa::ReferencePoint r = reference_->At(s.time_s);
    const double mass_kg = params_.quad_mass_kg + params_.payload_mass_kg;
    const Eigen::Vector3d force_W =
        mass_kg * (Eigen::Vector3d(0, 0, params_.gravity_mps2) + 4.0 * (r.p_WQ_W - s.p_WQ_W) +
                   3.0 * (r.v_WQ_W - s.v_WQ_W));
    const Eigen::Matrix3d R = s.q_WB.toRotationMatrix();
    const Eigen::Vector3d b3 = force_W.normalized();
    const Eigen::Vector3d b2 = b3.cross(Eigen::Vector3d::UnitX()).normalized();
    Eigen::Matrix3d Rd;
    Rd << b2.cross(b3), b2, b3;
    const Eigen::Matrix3d E = Rd.transpose() * R - R.transpose() * Rd;
    hpa::ControlOutput out;
    out.command.w_B_radps = -6.0 * 0.5 * Eigen::Vector3d(E(2, 1), E(0, 2), E(1, 0));
    out.command.thrust_N = std::max(0.0, force_W.dot(R.col(2)));
    return out;
  }
  double RateHz() const override { return 100.0; }

 private:
  hpa::Params params_;
  std::shared_ptr<const hpa::Reference> reference_;
};

}  // namespace

hpa::ControllerRegistration PdHoverRegistration() {
  return {"pd_hover", "a PD hover controller built out of tree", "hybrid",
          [](const hpa::ControllerConfig&, const hpa::Params& params,
             std::shared_ptr<const hpa::Reference> reference) {
            return std::make_unique<PdHover>(params, std::move(reference));
          }};
}
