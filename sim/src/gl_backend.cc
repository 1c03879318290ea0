#include "hpa/sim/gl_backend.h"

#include <stdexcept>

namespace hpa::sim {

namespace {
constexpr GlBackend kAllBackends[] = {GlBackend::kOsMesa, GlBackend::kEgl};
}  // namespace

GlBackend ParseGlBackend(const std::string& name) {
  std::string accepted;
  for (const GlBackend backend : kAllBackends) {
    if (name == GlBackendName(backend)) return backend;
    accepted += (accepted.empty() ? "" : " or ") + GlBackendName(backend);
  }
  throw std::invalid_argument("unknown GL back end '" + name + "' (expected " + accepted + ")");
}

std::string GlBackendName(GlBackend backend) {
  switch (backend) {
    case GlBackend::kOsMesa:
      return "osmesa";
    case GlBackend::kEgl:
      return "egl";
  }
  return "?";
}

}  // namespace hpa::sim
