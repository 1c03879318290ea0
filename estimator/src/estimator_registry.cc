#include "hpa/estimator/estimator_registry.h"

#include <utility>

#include "hpa/models/registry.h"

namespace hpa {

// Constructors of the built-in variants, each defined beside its filters (estimator.cc).
std::unique_ptr<Estimator> MakeHybridEstimator(const EstimatorConfig&, const Params&,
                                               const SystemState&);
std::unique_ptr<Estimator> MakeAlwaysTautEstimator(const EstimatorConfig&, const Params&,
                                                   const SystemState&);
std::unique_ptr<Estimator> MakeAlwaysTautProjectedEstimator(const EstimatorConfig&, const Params&,
                                                            const SystemState&);

namespace {

// The built-in variants, one line each.
Registry<EstimatorRegistration>& TheRegistry() {
  static Registry<EstimatorRegistration> registry(
      "estimator",
      {
          {"hybrid",
           "IMU+VIO filter, cable EKF, slack/taut mode detector, free-fall payload tracker",
           MakeHybridEstimator},
          {"always_taut",
           "the paper's baseline: mode always taut, payload position and velocity as measured",
           MakeAlwaysTautEstimator},
          {"always_taut_projected",
           "mode always taut, payload projected on the cable sphere at x_Q + l xi (cable EKF)",
           MakeAlwaysTautProjectedEstimator},
      });
  return registry;
}

}  // namespace

const std::vector<EstimatorRegistration>& Estimators() { return TheRegistry().All(); }

const EstimatorRegistration* FindEstimator(const std::string& name) {
  return TheRegistry().Find(name);
}

std::vector<std::string> EstimatorNames() { return TheRegistry().Names(); }

void RegisterEstimator(EstimatorRegistration registration) {
  TheRegistry().Add(std::move(registration));
}

std::unique_ptr<Estimator> MakeEstimator(const std::string& name, const EstimatorConfig& config,
                                         const Params& params, const SystemState& initial) {
  return TheRegistry().Get(name, "estimator").make(config, params, initial);
}

}  // namespace hpa
