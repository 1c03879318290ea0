#include "gl_context.h"

#include <mutex>
#include <optional>
#include <stdexcept>

namespace hpa::sim {

std::unique_ptr<GlContext> GlContext::Create(GlBackend backend, int max_width_px,
                                             int max_height_px) {
  // the back end of the process's first context is the only one MuJoCo's GL pointers reach
  // (gl_context.h)
  static std::mutex mutex;
  static std::optional<GlBackend> process_backend;
  const std::lock_guard<std::mutex> lock(mutex);
  if (process_backend && *process_backend != backend) {
    throw std::runtime_error("GL back end " + GlBackendName(backend) +
                             " requested, but this process already renders with " +
                             GlBackendName(*process_backend) +
                             " (MuJoCo 2.2 loads its GL functions once per process)");
  }
  std::unique_ptr<GlContext> context = backend == GlBackend::kEgl
                                           ? CreateEglContext()
                                           : CreateOsMesaContext(max_width_px, max_height_px);
  process_backend = backend;
  return context;
}

}  // namespace hpa::sim
