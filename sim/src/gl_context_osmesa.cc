// OSMesa: Mesa's llvmpipe rendering into client memory, no display or GPU needed (CI's path).

#include <GL/osmesa.h>

#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "gl_context.h"

namespace hpa::sim {
namespace {

class OsMesaGlContext final : public GlContext {
 public:
  OsMesaGlContext(int max_width_px, int max_height_px)
      : width_px_(max_width_px), height_px_(max_height_px) {
    context_ = OSMesaCreateContextExt(OSMESA_RGBA, 24, 8, 8, nullptr);
    if (context_ == nullptr) throw std::runtime_error("OSMesa: OSMesaCreateContextExt failed");
    window_buffer_.resize(static_cast<size_t>(width_px_) * height_px_ * 4);
    try {
      MakeCurrent();
    } catch (...) {
      OSMesaDestroyContext(context_);
      throw;
    }
  }

  ~OsMesaGlContext() override { OSMesaDestroyContext(context_); }

  void MakeCurrent() override {
    if (OSMesaGetCurrentContext() == context_) return;
    if (!OSMesaMakeCurrent(context_, window_buffer_.data(), GL_UNSIGNED_BYTE, width_px_,
                           height_px_)) {
      throw std::runtime_error("OSMesa: OSMesaMakeCurrent failed");
    }
  }

  GlBackend backend() const override { return GlBackend::kOsMesa; }
  int max_width_px() const override { return width_px_; }
  int max_height_px() const override { return height_px_; }

  std::string Description() override {
    MakeCurrent();
    const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    return std::string("OSMesa, ") + (renderer ? renderer : "unknown renderer");
  }

 private:
  OSMesaContext context_ = nullptr;
  std::vector<unsigned char> window_buffer_;  // OSMesa's default framebuffer (unused for drawing)
  int width_px_ = 0, height_px_ = 0;          // its size
};

}  // namespace

std::unique_ptr<GlContext> CreateOsMesaContext(int max_width_px, int max_height_px) {
  // llvmpipe rasterizes on the calling thread unless LP_NUM_THREADS says otherwise: on the
  // regions the payload camera reads, handing tiles to its worker threads costs more than they
  // save, and they compete with the control thread and a sweep's other workers. The pixels are
  // the same (each tile is rasterized the same by whichever thread). Read when Mesa makes its
  // screen, at the first context.
  static const bool kThreadsChosen = [] { return setenv("LP_NUM_THREADS", "0", 0) == 0; }();
  (void)kThreadsChosen;
  return std::make_unique<OsMesaGlContext>(max_width_px, max_height_px);
}

}  // namespace hpa::sim
