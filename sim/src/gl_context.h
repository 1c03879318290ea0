#pragma once
// A headless OpenGL context for MuJoCo's renderer, from OSMesa or EGL (docs/design.md section 9).
//
// MuJoCo 2.2 resolves its GL function pointers once per process, on the first mjr_makeContext,
// through the first of eglGetProcAddress, OSMesaGetProcAddress and glXGetProcAddressARB it
// finds among the process's global symbols. Pointers resolved for one back end do not reliably
// reach a context of the other (glvnd's EGL entry points do nothing under OSMesa; Mesa's do
// nothing under a GPU vendor's EGL), so a process renders with one back end only: Create
// refuses the other one once a context exists.

#include <memory>
#include <string>

#include "hpa/sim/gl_backend.h"

namespace hpa::sim {

/// An OpenGL (compatibility profile) context without a window; MuJoCo draws into its own
/// offscreen framebuffer object, so the context needs no drawable of its own.
class GlContext {
 public:
  /// Creates a context of `backend` and makes it current on this thread; max_width_px x
  /// max_height_px is the largest frame rendered (OSMesa's default framebuffer size). Throws
  /// std::runtime_error naming the back end, the failing call and its error code, or saying
  /// that this process already renders with the other back end.
  static std::unique_ptr<GlContext> Create(GlBackend backend, int max_width_px, int max_height_px);

  virtual ~GlContext() = default;

  /// Makes this context current on the calling thread (a no-op if it already is); throws
  /// std::runtime_error if the library refuses.
  virtual void MakeCurrent() = 0;

  /// The back end this context comes from.
  virtual GlBackend backend() const = 0;

  /// What renders: the back end, EGL's platform and GL_RENDERER (makes the context current).
  virtual std::string Description() = 0;
  /// The largest frame, as passed to Create.
  virtual int max_width_px() const = 0;
  /// The largest frame's height, as passed to Create.
  virtual int max_height_px() const = 0;

  /// Turns context reuse on or off for this process (off by default). While on, Recycle keeps
  /// an OSMesa context whose renderer is done, and the next Create of the same back end and
  /// size takes it, with what llvmpipe compiled for it (its shaders): a sweep renders one frame
  /// before forking so that every run starts with compiled shaders instead of compiling its own.
  static void SetReuse(bool on);
  /// Whether reuse is on (SetReuse).
  static bool reuse_on();
  /// Whether this process has created a context (llvmpipe has started).
  static bool created_any();
  /// Keeps `context` (its MuJoCo resources freed) for the next Create while reuse is on and it
  /// is an OSMesa context; otherwise destroys it.
  static void Recycle(std::unique_ptr<GlContext> context);
};

/// OSMesa context (gl_context_osmesa.cc); called by GlContext::Create only.
std::unique_ptr<GlContext> CreateOsMesaContext(int max_width_px, int max_height_px);

/// EGL context (gl_context_egl.cc); called by GlContext::Create only.
std::unique_ptr<GlContext> CreateEglContext();

}  // namespace hpa::sim
