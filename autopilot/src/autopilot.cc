#include "hpa/autopilot/autopilot.h"

namespace hpa {
namespace {

// The project's own body-rate loop (body_rate_controller.h) on the estimated body rate.
class OwnAutopilot final : public Autopilot {
 public:
  OwnAutopilot(const Params& params, double rate_hz)
      : params_(params), loop_(params), dt_s_(1.0 / rate_hz) {}
  bool RunsOnGyro() const override { return false; }
  AutopilotOutput Update(const BodyRateCommand& command,
                         const Eigen::Vector3d& w_B_radps) override {
    AutopilotOutput out;
    out.w_cmd_radps = loop_.Update(command, w_B_radps, dt_s_);
    out.thrust_allocated_N = params_.k_f_N_per_radps2 * out.w_cmd_radps.squaredNorm();
    // thrust priority clamps the collective thrust only where the motors cannot give it
    constexpr double kThrustShortfallN = 1e-6;
    out.saturated = out.thrust_allocated_N < command.thrust_N - kThrustShortfallN;
    return out;
  }

 private:
  Params params_;
  BodyRateController loop_;
  double dt_s_;
};

// PX4's rate loop and allocation (px4_rate_controller.h) on the rate gyro's samples.
class Px4Autopilot final : public Autopilot {
 public:
  Px4Autopilot(const Params& params, const Px4RateParams& px4) : loop_(params, px4) {}
  bool RunsOnGyro() const override { return true; }
  AutopilotOutput Update(const BodyRateCommand& command,
                         const Eigen::Vector3d& w_B_radps) override {
    AutopilotOutput out;
    out.w_cmd_radps = loop_.Update(command, w_B_radps);
    const Px4RateStatus& mixer = loop_.status();
    out.thrust_allocated_N = mixer.thrust_allocated_N;
    out.saturated = mixer.saturated;
    return out;
  }

 private:
  Px4RateController loop_;
};

}  // namespace

std::unique_ptr<Autopilot> MakeAutopilot(const Params& params, const RateLoopSpec& spec,
                                         double rate_hz) {
  if (spec.px4) return std::make_unique<Px4Autopilot>(params, spec.params);
  return std::make_unique<OwnAutopilot>(params, rate_hz);
}

}  // namespace hpa
