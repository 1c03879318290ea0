// EGL without a window or X server: a GPU's EGL device (EGL_EXT_platform_device: cluster GPU
// nodes), else Mesa's surfaceless platform, else Mesa's software device. The context has no
// surface (EGL_KHR_surfaceless_context): MuJoCo renders into its own framebuffer object.
//
// libEGL is loaded with dlopen, not linked. MuJoCo 2.2 takes its GL functions from the first
// eglGetProcAddress / OSMesaGetProcAddress it finds among the process's global symbols
// (gl_context.h). Linked, libEGL's eglGetProcAddress would be found first in every process,
// OSMesa runs included, and glvnd's GL entry points it returns do nothing under OSMesa (MuJoCo
// then fails with "gladLoadGL error"). Loaded here with RTLD_GLOBAL, it becomes visible only in
// processes that chose EGL, and there MuJoCo's GL calls go through glvnd to whichever vendor
// (Mesa, a GPU driver) owns the context.

#define EGL_NO_X11
#define MESA_EGL_NO_X11_HEADERS
#define EGL_EGL_PROTOTYPES 0  // every entry point through EglApi: no link-time libEGL
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/gl.h>
#include <dlfcn.h>

#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "gl_context.h"

namespace hpa::sim {
namespace {

// libEGL's entry points this file uses.
struct EglApi {
  PFNEGLGETPROCADDRESSPROC GetProcAddress = nullptr;
  PFNEGLGETERRORPROC GetError = nullptr;
  PFNEGLQUERYSTRINGPROC QueryString = nullptr;
  PFNEGLINITIALIZEPROC Initialize = nullptr;
  PFNEGLBINDAPIPROC BindAPI = nullptr;
  PFNEGLCHOOSECONFIGPROC ChooseConfig = nullptr;
  PFNEGLCREATECONTEXTPROC CreateContext = nullptr;
  PFNEGLDESTROYCONTEXTPROC DestroyContext = nullptr;
  PFNEGLMAKECURRENTPROC MakeCurrent = nullptr;
  PFNEGLGETCURRENTCONTEXTPROC GetCurrentContext = nullptr;
  PFNEGLGETPLATFORMDISPLAYEXTPROC GetPlatformDisplayEXT = nullptr;  // EGL_EXT_platform_base
  PFNEGLQUERYDEVICESEXTPROC QueryDevicesEXT = nullptr;              // EGL_EXT_device_enumeration
  PFNEGLQUERYDEVICESTRINGEXTPROC QueryDeviceStringEXT = nullptr;    // EGL_EXT_device_query
};

// EGL's name of an error code (eglGetError), with the code in hex.
std::string EglErrorText(EGLint code) {
  static const struct {
    EGLint code;
    const char* name;
  } kNames[] = {
      {EGL_SUCCESS, "EGL_SUCCESS"},
      {EGL_NOT_INITIALIZED, "EGL_NOT_INITIALIZED"},
      {EGL_BAD_ACCESS, "EGL_BAD_ACCESS"},
      {EGL_BAD_ALLOC, "EGL_BAD_ALLOC"},
      {EGL_BAD_ATTRIBUTE, "EGL_BAD_ATTRIBUTE"},
      {EGL_BAD_CONFIG, "EGL_BAD_CONFIG"},
      {EGL_BAD_CONTEXT, "EGL_BAD_CONTEXT"},
      {EGL_BAD_CURRENT_SURFACE, "EGL_BAD_CURRENT_SURFACE"},
      {EGL_BAD_DISPLAY, "EGL_BAD_DISPLAY"},
      {EGL_BAD_MATCH, "EGL_BAD_MATCH"},
      {EGL_BAD_NATIVE_PIXMAP, "EGL_BAD_NATIVE_PIXMAP"},
      {EGL_BAD_NATIVE_WINDOW, "EGL_BAD_NATIVE_WINDOW"},
      {EGL_BAD_PARAMETER, "EGL_BAD_PARAMETER"},
      {EGL_BAD_SURFACE, "EGL_BAD_SURFACE"},
      {EGL_CONTEXT_LOST, "EGL_CONTEXT_LOST"},
  };
  char hex[16];
  std::snprintf(hex, sizeof(hex), "0x%04X", static_cast<unsigned>(code));
  for (const auto& n : kNames) {
    if (n.code == code) return std::string(n.name) + ", " + hex;
  }
  return std::string("unknown error ") + hex;
}

// "eglX failed (EGL_BAD_Y, 0x300Z)" for the call that just failed.
std::string Failed(const EglApi& egl, const std::string& call) {
  return call + " failed (" + EglErrorText(egl.GetError()) + ")";
}

// True if the space-separated extension list names `extension`.
bool HasExtension(const char* list, const std::string& extension) {
  if (list == nullptr) return false;
  std::istringstream words(list);
  for (std::string word; words >> word;) {
    if (word == extension) return true;
  }
  return false;
}

// libEGL, loaded once per process and never unloaded (MuJoCo keeps pointers into it); throws
// std::runtime_error if the library or an entry point is missing.
const EglApi& LoadEgl() {
  static const EglApi api = [] {
    // RTLD_GLOBAL: MuJoCo must find this eglGetProcAddress (see the top of this file)
    void* library = dlopen("libEGL.so.1", RTLD_NOW | RTLD_GLOBAL);
    if (library == nullptr) {
      throw std::runtime_error(std::string("EGL: dlopen(libEGL.so.1) failed: ") + dlerror());
    }
    EglApi egl;
    const auto load = [library](auto* function, const char* name) {
      *function = reinterpret_cast<std::remove_pointer_t<decltype(function)>>(dlsym(library, name));
      if (*function == nullptr) {
        throw std::runtime_error(std::string("EGL: libEGL.so.1 has no ") + name);
      }
    };
    load(&egl.GetProcAddress, "eglGetProcAddress");
    load(&egl.GetError, "eglGetError");
    load(&egl.QueryString, "eglQueryString");
    load(&egl.Initialize, "eglInitialize");
    load(&egl.BindAPI, "eglBindAPI");
    load(&egl.ChooseConfig, "eglChooseConfig");
    load(&egl.CreateContext, "eglCreateContext");
    load(&egl.DestroyContext, "eglDestroyContext");
    load(&egl.MakeCurrent, "eglMakeCurrent");
    load(&egl.GetCurrentContext, "eglGetCurrentContext");
    // extensions: null when the implementation lacks them
    egl.GetPlatformDisplayEXT = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        egl.GetProcAddress("eglGetPlatformDisplayEXT"));
    egl.QueryDevicesEXT =
        reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(egl.GetProcAddress("eglQueryDevicesEXT"));
    egl.QueryDeviceStringEXT = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
        egl.GetProcAddress("eglQueryDeviceStringEXT"));
    return egl;
  }();
  return api;
}

// An initialised EGL display and the platform it came from.
struct EglDisplay {
  EGLDisplay display = EGL_NO_DISPLAY;
  std::string platform;  // "surfaceless" or "device N"
};

// Initialises `display` (from eglGetPlatformDisplayEXT of `what`); on failure, appends why to
// `why_not` and returns false.
bool InitializeDisplay(const EglApi& egl, EGLDisplay display, const std::string& what,
                       std::string* why_not) {
  if (display == EGL_NO_DISPLAY) {
    *why_not += "; " + Failed(egl, "eglGetPlatformDisplayEXT(" + what + ")");
    return false;
  }
  EGLint major = 0, minor = 0;
  if (egl.Initialize(display, &major, &minor) != EGL_TRUE) {
    *why_not += "; " + Failed(egl, "eglInitialize(" + what + ")");
    return false;
  }
  return true;
}

// True for Mesa's software (llvmpipe) device.
bool IsSoftwareDevice(const EglApi& egl, EGLDeviceEXT device) {
  return egl.QueryDeviceStringEXT != nullptr &&
         HasExtension(egl.QueryDeviceStringEXT(device, EGL_EXTENSIONS), "EGL_MESA_device_software");
}

// The EGL devices (EGL_EXT_device_enumeration) in eglQueryDevicesEXT's order; appends why to
// `why_not` when there are none.
std::vector<EGLDeviceEXT> Devices(const EglApi& egl, const char* client_extensions,
                                  std::string* why_not) {
  if (egl.QueryDevicesEXT == nullptr ||
      !HasExtension(client_extensions, "EGL_EXT_platform_device")) {
    *why_not += "; no client extension EGL_EXT_device_enumeration + EGL_EXT_platform_device";
    return {};
  }
  EGLint count = 0;
  if (egl.QueryDevicesEXT(0, nullptr, &count) != EGL_TRUE) {
    *why_not += "; " + Failed(egl, "eglQueryDevicesEXT");
    return {};
  }
  std::vector<EGLDeviceEXT> devices(count);
  if (count > 0 && egl.QueryDevicesEXT(count, devices.data(), &count) != EGL_TRUE) {
    *why_not += "; " + Failed(egl, "eglQueryDevicesEXT");
    return {};
  }
  devices.resize(count);
  if (devices.empty()) *why_not += "; eglQueryDevicesEXT found no device";
  return devices;
}

// The process's EGL display, initialised once and never terminated: every renderer's context
// lives on it, and eglTerminate would end them all. A GPU's EGL device first (a GPU vendor's
// driver, e.g. NVIDIA's, has no surfaceless platform, and Mesa's surfaceless platform on such a
// node would fall back to llvmpipe), then Mesa's surfaceless platform, then a software device.
// Throws std::runtime_error listing each attempt's failing call and error code.
const EglDisplay& Display(const EglApi& egl) {
  static const EglDisplay display = [&egl] {
    if (egl.GetPlatformDisplayEXT == nullptr) {
      throw std::runtime_error("EGL: no eglGetPlatformDisplayEXT (EGL_EXT_platform_base)");
    }
    const char* client_extensions = egl.QueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    std::string why_not;
    const std::vector<EGLDeviceEXT> devices = Devices(egl, client_extensions, &why_not);
    const auto try_device = [&](size_t i, EglDisplay* out) {
      const std::string what = "EGL_PLATFORM_DEVICE_EXT, device " + std::to_string(i);
      const EGLDisplay d = egl.GetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
      if (!InitializeDisplay(egl, d, what, &why_not)) return false;
      *out = EglDisplay{d, "device " + std::to_string(i)};
      return true;
    };
    EglDisplay result;
    // GPU devices
    for (size_t i = 0; i < devices.size(); ++i) {
      if (!IsSoftwareDevice(egl, devices[i]) && try_device(i, &result)) return result;
    }
    // Mesa's surfaceless platform: no display server; a render node or llvmpipe
    if (HasExtension(client_extensions, "EGL_MESA_platform_surfaceless")) {
      const EGLDisplay d =
          egl.GetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
      if (InitializeDisplay(egl, d, "EGL_PLATFORM_SURFACELESS_MESA", &why_not)) {
        return EglDisplay{d, "surfaceless"};
      }
    } else {
      why_not += "; no client extension EGL_MESA_platform_surfaceless";
    }
    // software devices
    for (size_t i = 0; i < devices.size(); ++i) {
      if (IsSoftwareDevice(egl, devices[i]) && try_device(i, &result)) return result;
    }
    throw std::runtime_error("EGL: no display" + why_not);
  }();
  return display;
}

class EglGlContext final : public GlContext {
 public:
  EglGlContext() : egl_(LoadEgl()), display_(Display(egl_)) {
    // desktop OpenGL; no version or profile attributes: EGL then creates a legacy
    // (compatibility) context of the highest version, which MuJoCo 2.2's fixed-function
    // renderer needs
    if (egl_.BindAPI(EGL_OPENGL_API) != EGL_TRUE) {
      throw std::runtime_error("EGL: " + Failed(egl_, "eglBindAPI(EGL_OPENGL_API)"));
    }
    const EGLint config_attributes[] = {EGL_RED_SIZE,
                                        8,
                                        EGL_GREEN_SIZE,
                                        8,
                                        EGL_BLUE_SIZE,
                                        8,
                                        EGL_ALPHA_SIZE,
                                        8,
                                        EGL_DEPTH_SIZE,
                                        24,
                                        EGL_STENCIL_SIZE,
                                        8,
                                        EGL_SURFACE_TYPE,
                                        EGL_PBUFFER_BIT,
                                        EGL_RENDERABLE_TYPE,
                                        EGL_OPENGL_BIT,
                                        EGL_NONE};
    EGLConfig config = nullptr;
    EGLint config_count = 0;
    if (egl_.ChooseConfig(display_.display, config_attributes, &config, 1, &config_count) !=
        EGL_TRUE) {
      throw std::runtime_error("EGL: " + Failed(egl_, "eglChooseConfig"));
    }
    if (config_count < 1) {
      throw std::runtime_error(
          "EGL: eglChooseConfig found no RGBA8, depth 24, stencil 8 OpenGL config on " +
          display_.platform);
    }
    if (!HasExtension(egl_.QueryString(display_.display, EGL_EXTENSIONS),
                      "EGL_KHR_surfaceless_context")) {
      throw std::runtime_error("EGL: display " + display_.platform +
                               " lacks EGL_KHR_surfaceless_context");
    }
    const EGLint context_attributes[] = {EGL_NONE};
    context_ = egl_.CreateContext(display_.display, config, EGL_NO_CONTEXT, context_attributes);
    if (context_ == EGL_NO_CONTEXT) {
      throw std::runtime_error("EGL: " + Failed(egl_, "eglCreateContext"));
    }
    try {
      MakeCurrent();
    } catch (...) {
      egl_.DestroyContext(display_.display, context_);
      throw;
    }
  }

  ~EglGlContext() override {
    if (egl_.GetCurrentContext() == context_) {
      egl_.MakeCurrent(display_.display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
    egl_.DestroyContext(display_.display, context_);
  }

  void MakeCurrent() override {
    if (egl_.GetCurrentContext() == context_) return;
    if (egl_.MakeCurrent(display_.display, EGL_NO_SURFACE, EGL_NO_SURFACE, context_) != EGL_TRUE) {
      throw std::runtime_error("EGL: " + Failed(egl_, "eglMakeCurrent"));
    }
  }

  GlBackend backend() const override { return GlBackend::kEgl; }
  int max_width_px() const override { return 0; }  // EGL contexts are never reused
  int max_height_px() const override { return 0; }

  std::string Description() override {
    MakeCurrent();
    using GetStringFunction = const GLubyte* (*)(GLenum);
    const auto get_string = reinterpret_cast<GetStringFunction>(egl_.GetProcAddress("glGetString"));
    const GLubyte* renderer = get_string ? get_string(GL_RENDERER) : nullptr;
    return "EGL " + display_.platform + ", " +
           (renderer ? reinterpret_cast<const char*>(renderer) : "unknown renderer");
  }

 private:
  const EglApi& egl_;
  const EglDisplay& display_;
  EGLContext context_ = EGL_NO_CONTEXT;
};

}  // namespace

std::unique_ptr<GlContext> CreateEglContext() { return std::make_unique<EglGlContext>(); }

}  // namespace hpa::sim
