#include "gl_context.h"

#include <mutex>
#include <optional>
#include <stdexcept>

namespace hpa::sim {
namespace {

std::mutex contexts_mutex;     // guards everything below and Create
bool reuse_contexts = false;   // GlContext::SetReuse
bool context_created = false;  // a context was made in this process

// The context kept for the next Create (GlContext::Recycle).
std::unique_ptr<GlContext>& SpareContext() {
  static std::unique_ptr<GlContext> spare;
  return spare;
}

}  // namespace

void GlContext::SetReuse(bool on) {
  const std::lock_guard<std::mutex> lock(contexts_mutex);
  reuse_contexts = on;
  if (!on) SpareContext().reset();
}

bool GlContext::reuse_on() {
  const std::lock_guard<std::mutex> lock(contexts_mutex);
  return reuse_contexts;
}

bool GlContext::created_any() {
  const std::lock_guard<std::mutex> lock(contexts_mutex);
  return context_created;
}

void GlContext::Recycle(std::unique_ptr<GlContext> context) {
  const std::lock_guard<std::mutex> lock(contexts_mutex);
  if (reuse_contexts && context != nullptr && context->backend() == GlBackend::kOsMesa) {
    SpareContext() = std::move(context);
  }
}

std::unique_ptr<GlContext> GlContext::Create(GlBackend backend, int max_width_px,
                                             int max_height_px) {
  // the back end of the process's first context is the only one MuJoCo's GL pointers reach
  // (gl_context.h)
  static std::optional<GlBackend> process_backend;
  const std::lock_guard<std::mutex> lock(contexts_mutex);
  if (process_backend && *process_backend != backend) {
    throw std::runtime_error("GL back end " + GlBackendName(backend) +
                             " requested, but this process already renders with " +
                             GlBackendName(*process_backend) +
                             " (MuJoCo 2.2 loads its GL functions once per process)");
  }
  if (backend == GlBackend::kOsMesa) {
    std::unique_ptr<GlContext>& spare = SpareContext();
    if (spare != nullptr && spare->max_width_px() == max_width_px &&
        spare->max_height_px() == max_height_px) {
      spare->MakeCurrent();
      return std::move(spare);
    }
  }
  std::unique_ptr<GlContext> context = backend == GlBackend::kEgl
                                           ? CreateEglContext()
                                           : CreateOsMesaContext(max_width_px, max_height_px);
  process_backend = backend;
  context_created = true;
  return context;
}

}  // namespace hpa::sim
