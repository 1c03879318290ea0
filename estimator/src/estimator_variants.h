#pragma once
// Constructors of the built-in estimator variants, listed by the registry
// (estimator_registry.cc); private to the estimator library.

#include <memory>

#include "hpa/estimator/estimator.h"

namespace hpa {

/// Quadrotor filter, cable EKF, mode detector and free-fall payload tracker (flies hpa_mpc).
std::unique_ptr<Estimator> MakeHybridEstimator(const EstimatorConfig& config, const Params& params,
                                               const SystemState& initial);
/// The paper's baseline estimator: mode always taut, payload as measured by the camera
/// (position of the newest detection, low-passed finite-difference velocity).
std::unique_ptr<Estimator> MakeAlwaysTautEstimator(const EstimatorConfig& config,
                                                   const Params& params,
                                                   const SystemState& initial);
/// Mode always taut, payload projected on the cable sphere at x_Q + l xi (cable EKF).
std::unique_ptr<Estimator> MakeAlwaysTautProjectedEstimator(const EstimatorConfig& config,
                                                            const Params& params,
                                                            const SystemState& initial);

}  // namespace hpa
