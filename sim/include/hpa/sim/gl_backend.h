#pragma once
// Which OpenGL context the rendered cameras use (docs/design.md section 9). Only names here: the GL
// headers stay inside sim/src.

#include <string>

namespace hpa::sim {

/// The library that provides the headless OpenGL context MuJoCo renders into.
enum class GlBackend {
  kOsMesa,  // Mesa's off-screen llvmpipe, CPU only: the default and what CI runs
  kEgl,     // EGL without a window: a GPU's driver where there is one (cluster GPU nodes)
};

/// Back end of a command-line name ("osmesa" or "egl"); throws std::invalid_argument naming the
/// bad value and the accepted ones.
GlBackend ParseGlBackend(const std::string& name);

/// The command-line name of a back end ("osmesa" or "egl").
std::string GlBackendName(GlBackend backend);

}  // namespace hpa::sim
