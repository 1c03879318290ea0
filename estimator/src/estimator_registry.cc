#include "hpa/estimator/estimator_registry.h"

#include <stdexcept>
#include <utility>

#include "estimator_variants.h"

namespace hpa {
namespace {

// The built-in variants, one line each.
std::vector<EstimatorRegistration> BuiltInEstimators() {
  return {
      {"hybrid", "IMU+VIO filter, cable EKF, slack/taut mode detector, free-fall payload tracker",
       MakeHybridEstimator},
      {"always_taut",
       "the paper's baseline: mode always taut, payload position and velocity as measured",
       MakeAlwaysTautEstimator},
      {"always_taut_projected",
       "mode always taut, payload projected on the cable sphere at x_Q + l xi (cable EKF)",
       MakeAlwaysTautProjectedEstimator},
  };
}

std::vector<EstimatorRegistration>& Registry() {
  static std::vector<EstimatorRegistration> registry = BuiltInEstimators();
  return registry;
}

std::string JoinedNames() {
  std::string joined;
  for (const std::string& name : EstimatorNames()) joined += (joined.empty() ? "" : ", ") + name;
  return joined;
}

}  // namespace

const std::vector<EstimatorRegistration>& Estimators() { return Registry(); }

const EstimatorRegistration* FindEstimator(const std::string& name) {
  for (const EstimatorRegistration& registration : Registry()) {
    if (registration.name == name) return &registration;
  }
  return nullptr;
}

std::vector<std::string> EstimatorNames() {
  std::vector<std::string> names;
  for (const EstimatorRegistration& registration : Registry()) names.push_back(registration.name);
  return names;
}

void RegisterEstimator(EstimatorRegistration registration) {
  if (registration.name.empty()) {
    throw std::invalid_argument("RegisterEstimator: empty estimator name");
  }
  if (!registration.make) {
    throw std::invalid_argument("RegisterEstimator: estimator '" + registration.name +
                                "' has no factory");
  }
  if (FindEstimator(registration.name) != nullptr) {
    throw std::invalid_argument("RegisterEstimator: estimator '" + registration.name +
                                "' is already registered");
  }
  Registry().push_back(std::move(registration));
}

std::unique_ptr<Estimator> MakeEstimator(const std::string& name, const EstimatorConfig& config,
                                         const Params& params, const SystemState& initial) {
  const EstimatorRegistration* registration = FindEstimator(name);
  if (registration == nullptr) {
    throw std::invalid_argument("estimator: unknown variant '" + name +
                                "' (known: " + JoinedNames() + ")");
  }
  return registration->make(config, params, initial);
}

}  // namespace hpa
