#pragma once
// A PD hover controller written outside hpa's tree: the quadrotor held above the payload reference
// from the state the flight code sees. Registered by name, it flies wherever hpa's own controllers
// do (hpa run --controller pd_hover, compare, sweeps).

#include "hpa/controller/controller_registry.h"

/// The controller's registration: name "pd_hover", flown with the hybrid estimator.
hpa::ControllerRegistration PdHoverRegistration();
