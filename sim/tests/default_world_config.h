#pragma once
// The world configuration sim tests start from: the shipped params.yaml, every other part at its
// default (the ideal world).

#include "hpa/models/params.h"
#include "hpa/sim/world.h"

namespace hpa::sim {

/// params.yaml and defaults elsewhere.
inline WorldConfig DefaultConfig() {
  WorldConfig c;
  c.params = LoadParams(DefaultParamsPath());
  return c;
}

}  // namespace hpa::sim
