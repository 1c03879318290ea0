#include "offscreen_renderer.h"

#include <GL/gl.h>

#include <cstring>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "gl_context.h"

namespace hpa::sim {

struct OffscreenRenderer::Gl {
  // Creates the GL context (current from here on) and MuJoCo's GL resources for `model`, with an
  // offscreen buffer of max_w x max_h; throws when MuJoCo gets no offscreen framebuffer.
  static std::unique_ptr<Gl> Create(const mjModel* model, GlBackend backend, int max_w, int max_h);

  // Reads the rendered viewport into `out` (the part of a width_px wide BGR frame it covers):
  // straight from a single-sample buffer, else resolved by MuJoCo, flipped and converted through
  // *flip_buffer.
  void ReadPixels(const mjrRect& viewport, int width_px, cv::Mat* out, cv::Mat* flip_buffer);

  std::unique_ptr<GlContext> context;  // OSMesa or EGL
  mjvScene scene;
  mjrContext render_context;
  mjvOption option;
  mjvCamera camera;
  std::vector<unsigned char> rgb;  // mjr_readPixels output, bottom row first (multisampled only)
  bool pack_invert = false;        // GL_MESA_pack_invert: glReadPixels writes the top row first
};

namespace {
// GL_MESA_pack_invert's pixel-store name (GL/glext.h is not needed for one constant).
constexpr GLenum kGlPackInvertMesa = 0x8758;

// Refuses a frame larger than the model's offscreen buffer or a camera the model does not have.
void CheckRenderRequest(const mjModel* model, int camera_id, int width_px, int height_px) {
  const int max_w = model->vis.global.offwidth;
  const int max_h = model->vis.global.offheight;
  if (width_px <= 0 || height_px <= 0 || width_px > max_w || height_px > max_h) {
    throw std::invalid_argument("OffscreenRenderer: " + std::to_string(width_px) + "x" +
                                std::to_string(height_px) + " outside the offscreen buffer " +
                                std::to_string(max_w) + "x" + std::to_string(max_h));
  }
  if (camera_id < 0 || camera_id >= model->ncam) {
    throw std::invalid_argument("OffscreenRenderer: no camera with id " +
                                std::to_string(camera_id));
  }
}

// Narrows both eyes' frusta to `area` of the width_px x height_px frame, so that rendering a
// viewport of area's size gives the frame's pixels there (MuJoCo sets left/right from
// frustum_center and the viewport's aspect ratio).
void NarrowFrustumToArea(const cv::Rect& area, int width_px, int height_px, mjvScene* scene) {
  for (int eye = 0; eye < 2; ++eye) {
    mjvGLCamera& c = scene->camera[eye];
    const float span = c.frustum_top - c.frustum_bottom;  // the frame's height at the near plane
    const float per_px = span / static_cast<float>(height_px);
    const float top = c.frustum_top - per_px * static_cast<float>(area.y);
    c.frustum_bottom = top - per_px * static_cast<float>(area.height);
    c.frustum_top = top;
    c.frustum_center += per_px * (static_cast<float>(area.x) + 0.5f * area.width - 0.5f * width_px);
  }
}

}  // namespace

std::unique_ptr<OffscreenRenderer::Gl> OffscreenRenderer::Gl::Create(const mjModel* model,
                                                                     GlBackend backend, int max_w,
                                                                     int max_h) {
  auto gl = std::make_unique<Gl>();
  gl->context = GlContext::Create(backend, max_w, max_h);
  mjv_defaultScene(&gl->scene);
  mjr_defaultContext(&gl->render_context);
  mjv_defaultOption(&gl->option);
  mjv_defaultCamera(&gl->camera);
  mjv_makeScene(model, &gl->scene, 200);
  mjr_makeContext(model, &gl->render_context, mjFONTSCALE_100);
  mjr_setBuffer(mjFB_OFFSCREEN, &gl->render_context);
  if (gl->render_context.currentBuffer != mjFB_OFFSCREEN) {
    mjr_freeContext(&gl->render_context);
    mjv_freeScene(&gl->scene);
    throw std::runtime_error("MuJoCo offscreen framebuffer not available under " +
                             GlBackendName(backend));
  }
  // speed (docs/design.md section 9): shadows, reflections and the skybox cost most of a frame
  gl->scene.flags[mjRND_SHADOW] = 0;
  gl->scene.flags[mjRND_REFLECTION] = 0;
  gl->scene.flags[mjRND_SKYBOX] = 0;
  // direct read-out calls libOSMesa's GL entry points: only under OSMesa (under EGL the GL
  // functions belong to whichever driver owns the context; MuJoCo's own read-out is used)
  if (backend == GlBackend::kOsMesa) {
    const char* extensions = reinterpret_cast<const char*>(glGetString(GL_EXTENSIONS));
    gl->pack_invert =
        extensions != nullptr && std::strstr(extensions, "GL_MESA_pack_invert") != nullptr;
  }
  if (gl->render_context.offSamples > 0 || !gl->pack_invert) {
    gl->rgb.resize(static_cast<size_t>(max_w) * max_h * 3);
  }
  return gl;
}

void OffscreenRenderer::Gl::ReadPixels(const mjrRect& viewport, int width_px, cv::Mat* out,
                                       cv::Mat* flip_buffer) {
  if (render_context.offSamples == 0 && pack_invert) {
    // single-sample buffer: read it straight into the image, BGR, top row first
    mjr_setBuffer(mjFB_OFFSCREEN, &render_context);  // offscreen FBO bound for reading
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glPixelStorei(GL_PACK_ROW_LENGTH, width_px);  // rows of the viewport inside the whole frame
    glPixelStorei(kGlPackInvertMesa, GL_TRUE);
    glReadPixels(0, 0, viewport.width, viewport.height, GL_BGR, GL_UNSIGNED_BYTE, out->data);
    glPixelStorei(kGlPackInvertMesa, GL_FALSE);
    glPixelStorei(GL_PACK_ROW_LENGTH, 0);
    return;
  }
  // multisampled buffer (MuJoCo resolves it in mjr_readPixels): rows bottom-up, RGB
  const size_t area_px = static_cast<size_t>(viewport.width) * viewport.height;
  if (rgb.size() < area_px * 3) rgb.resize(area_px * 3);
  mjr_readPixels(rgb.data(), nullptr, viewport, &render_context);
  const cv::Mat rgb_bottom_up(viewport.height, viewport.width, CV_8UC3, rgb.data());
  cv::flip(rgb_bottom_up, *flip_buffer, 0);
  cv::cvtColor(*flip_buffer, *out, cv::COLOR_RGB2BGR);
}

OffscreenRenderer::OffscreenRenderer(const mjModel* model, GlBackend backend)
    : model_(model), backend_(backend) {}

OffscreenRenderer::~OffscreenRenderer() {
  if (gl_ == nullptr) return;
  try {
    gl_->context->MakeCurrent();  // MuJoCo frees the GL objects of the current context
    mjr_freeContext(&gl_->render_context);
    GlContext::Recycle(std::move(gl_->context));  // kept for the next renderer if reuse is on
  } catch (const std::runtime_error&) {
    // the context cannot be made current: its GL objects go with it
  }
  mjv_freeScene(&gl_->scene);
}

void OffscreenRenderer::SetGeomGroupVisible(int group, bool visible) {
  if (group >= 0 && group < mjNGROUP) geom_group_visible_[group] = visible;
}

bool OffscreenRenderer::initialized() const { return gl_ != nullptr; }

std::string OffscreenRenderer::GlDescription() {
  return gl_ == nullptr ? "" : gl_->context->Description();
}

cv::Mat OffscreenRenderer::Render(mjData* data, int camera_id, int width_px, int height_px,
                                  bool show_tendons) {
  cv::Mat bgr;
  Render(data, camera_id, width_px, height_px, show_tendons, &bgr);
  return bgr;
}

void OffscreenRenderer::Render(mjData* data, int camera_id, int width_px, int height_px,
                               bool show_tendons, cv::Mat* bgr, const cv::Rect& region) {
  CheckRenderRequest(model_, camera_id, width_px, height_px);
  // first frame: create the GL context (current from here on) and MuJoCo's GL resources
  if (gl_ == nullptr) {
    gl_ = Gl::Create(model_, backend_, model_->vis.global.offwidth, model_->vis.global.offheight);
  }
  gl_->context->MakeCurrent();  // another renderer may have made its own current since

  // scene from the current kinematics, seen from the fixed camera
  gl_->camera.type = mjCAMERA_FIXED;
  gl_->camera.fixedcamid = camera_id;
  for (int g = 0; g < mjNGROUP; ++g) {
    gl_->option.tendongroup[g] = show_tendons ? 1 : 0;
    gl_->option.geomgroup[g] = geom_group_visible_[g] ? 1 : 0;
  }
  mjv_updateScene(model_, data, &gl_->option, nullptr, &gl_->camera, mjCAT_ALL, &gl_->scene);
  bgr->create(height_px, width_px, CV_8UC3);  // no allocation when the size is unchanged
  const cv::Rect frame(0, 0, width_px, height_px);
  const cv::Rect area = region.area() > 0 ? (region & frame) : frame;
  if (area.area() == 0) return;
  // only `area` of the frame: the frustum narrowed to it, so its pixels are the frame's
  if (area != frame) NarrowFrustumToArea(area, width_px, height_px, &gl_->scene);
  const mjrRect viewport = {0, 0, area.width, area.height};
  mjr_render(viewport, &gl_->scene, &gl_->render_context);
  cv::Mat out = (*bgr)(area);
  gl_->ReadPixels(viewport, width_px, &out, &flip_buffer_);
}

}  // namespace hpa::sim
