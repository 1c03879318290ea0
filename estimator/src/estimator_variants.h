#pragma once
// Constructors of the built-in estimator variants, listed by the registry
// (estimator_registry.cc); private to the estimator library.

#include <memory>

#include "hpa/estimator/estimator.h"

namespace hpa {

/// Quadrotor filter, cable EKF, mode detector and free-fall payload tracker (flies hpa_mpc).
std::unique_ptr<Estimator> MakeHybridEstimator(const EstimatorConfig& config, const Params& params,
                                               const SystemState& initial);
/// Quadrotor filter and cable EKF only: mode always taut, payload at x_Q + l xi.
std::unique_ptr<Estimator> MakeAlwaysTautEstimator(const EstimatorConfig& config,
                                                   const Params& params,
                                                   const SystemState& initial);

}  // namespace hpa
