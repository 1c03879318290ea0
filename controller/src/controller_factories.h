#pragma once
// Factories of the built-in controllers, listed once by controller_registry.cc; private to the
// controller library.

#include <memory>

#include "hpa/controller/controller.h"

namespace hpa {

/// HPA-MPC: hybrid taut/slack model, mode from the estimate, perception cost on.
std::unique_ptr<Controller> MakeHpaMpcController(const ControllerConfig& config,
                                                 const Params& params,
                                                 std::shared_ptr<const Reference> reference);
/// The paper's non-hybrid baseline: always-taut model, payload cost only.
std::unique_ptr<Controller> MakeNonhybridMpcController(const ControllerConfig& config,
                                                       const Params& params,
                                                       std::shared_ptr<const Reference> reference);
/// Geometric controller on the quadrotor (Lee et al.) tracking the flatness reference.
std::unique_ptr<Controller> MakeGeometricController(const ControllerConfig& config,
                                                    const Params& params,
                                                    std::shared_ptr<const Reference> reference);

}  // namespace hpa
