#pragma once
// The one list of estimator variants: scenarios name a variant, the CLI lists them for --help,
// and a new variant is its own files plus one line in estimator_registry.cc.

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hpa/estimator/estimator.h"
#include "hpa/models/params.h"
#include "hpa/models/state.h"

namespace hpa {

/// Builds an estimator variant from its config, the flight params and the initial state.
using EstimatorFactory = std::function<std::unique_ptr<Estimator>(
    const EstimatorConfig&, const Params&, const SystemState& initial)>;

/// One registered estimator variant.
struct EstimatorRegistration {
  std::string name;         // as written in scenarios (estimation.estimator)
  std::string description;  // one line for --help
  EstimatorFactory make;    // builds it
};

/// Every registered variant, built-in ones first, in registration order.
const std::vector<EstimatorRegistration>& Estimators();
/// The variant called `name`, or nullptr; valid until the next RegisterEstimator.
const EstimatorRegistration* FindEstimator(const std::string& name);
/// The names of every registered variant, in registration order.
std::vector<std::string> EstimatorNames();
/// Adds a variant; throws std::invalid_argument on an empty name, a missing factory or a name
/// already registered.
void RegisterEstimator(EstimatorRegistration registration);
/// Builds the variant `name`; throws std::invalid_argument naming the known variants.
std::unique_ptr<Estimator> MakeEstimator(const std::string& name, const EstimatorConfig& config,
                                         const Params& params, const SystemState& initial);

}  // namespace hpa
