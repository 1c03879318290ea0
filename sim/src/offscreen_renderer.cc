#include "offscreen_renderer.h"

#include <GL/gl.h>

#include <cstdint>
#include <cstring>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "gl_context.h"
#include "scene_culling.h"

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
  uint64_t model_signature = 0;        // RenderSignature of the model the resources were made for
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

// FNV-1a over `bytes` bytes at `data`, continuing from `hash`.
uint64_t Fnv1a(const void* data, size_t bytes, uint64_t hash) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < bytes; ++i) hash = (hash ^ p[i]) * 0x100000001b3ull;
  return hash;
}

// A hash of everything in `model` that mjr_makeContext and mjv_makeScene read (the visual
// settings, the extent, the planes' grids, materials and textures), so that two models with the
// same signature get the same GL resources; 0 for a model with meshes, height fields or skins,
// whose resources are never shared.
uint64_t RenderSignature(const mjModel* m) {
  if (m->nmesh > 0 || m->nhfield > 0 || m->nskin > 0) return 0;
  uint64_t h = 0xcbf29ce484222325ull;
  const auto mix = [&h](const void* data, size_t bytes) { h = Fnv1a(data, bytes, h); };
  mix(&m->vis, sizeof m->vis);
  mix(&m->stat.extent, sizeof m->stat.extent);
  mix(&m->ngeom, sizeof m->ngeom);
  mix(m->geom_type, sizeof(int) * m->ngeom);
  mix(m->geom_size, sizeof(mjtNum) * 3 * m->ngeom);
  mix(m->geom_matid, sizeof(int) * m->ngeom);
  mix(m->geom_dataid, sizeof(int) * m->ngeom);
  mix(&m->nmat, sizeof m->nmat);
  mix(m->mat_texid, sizeof(int) * m->nmat);
  mix(m->mat_texuniform, sizeof(mjtByte) * m->nmat);
  mix(m->mat_texrepeat, sizeof(float) * 2 * m->nmat);
  mix(&m->ntex, sizeof m->ntex);
  mix(m->tex_type, sizeof(int) * m->ntex);
  mix(m->tex_height, sizeof(int) * m->ntex);
  mix(m->tex_width, sizeof(int) * m->ntex);
  mix(m->tex_adr, sizeof(int) * m->ntex);
  mix(&m->ntexdata, sizeof m->ntexdata);
  mix(m->tex_rgb, sizeof(mjtByte) * m->ntexdata);
  return h == 0 ? 1 : h;
}

std::mutex& KeptGlMutex() {
  static std::mutex mutex;
  return mutex;
}

}  // namespace

std::unique_ptr<OffscreenRenderer::Gl>& OffscreenRenderer::KeptGl() {
  static std::unique_ptr<Gl> kept;
  return kept;
}

void OffscreenRenderer::Release(std::unique_ptr<Gl> gl) {
  if (gl == nullptr) return;
  try {
    gl->context->MakeCurrent();  // MuJoCo frees the GL objects of the current context
    mjr_freeContext(&gl->render_context);
    GlContext::Recycle(std::move(gl->context));  // kept for the next renderer if reuse is on
  } catch (const std::runtime_error&) {
    // the context cannot be made current: its GL objects go with it
  }
  mjv_freeScene(&gl->scene);
}

std::unique_ptr<OffscreenRenderer::Gl> OffscreenRenderer::Gl::Create(const mjModel* model,
                                                                     GlBackend backend, int max_w,
                                                                     int max_h) {
  auto gl = std::make_unique<Gl>();
  gl->context = GlContext::Create(backend, max_w, max_h);
  gl->model_signature = RenderSignature(model);
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
  // while reuse is on, the whole state is kept for the next renderer of a model that renders
  // the same (a sweep's runs): MuJoCo's GL resources are not made again
  if (GlContext::reuse_on() && gl_->model_signature != 0 &&
      gl_->context->backend() == GlBackend::kOsMesa) {
    std::unique_ptr<Gl> previous;
    {
      const std::lock_guard<std::mutex> lock(KeptGlMutex());
      previous = std::exchange(KeptGl(), std::move(gl_));
    }
    Release(std::move(previous));
    return;
  }
  Release(std::move(gl_));
}

void OffscreenRenderer::SetGeomGroupVisible(int group, bool visible) {
  if (group >= 0 && group < mjNGROUP) geom_group_visible_[group] = visible;
}

void OffscreenRenderer::SetCullHiddenGeoms(bool cull) { cull_hidden_geoms_ = cull; }

bool OffscreenRenderer::initialized() const { return gl_ != nullptr; }

std::string OffscreenRenderer::GlDescription() {
  return gl_ == nullptr ? "" : gl_->context->Description();
}

void OffscreenRenderer::Prepare() {
  // the first time: the state another renderer kept for a model that renders the same, else a
  // new GL context (current from here on) and MuJoCo's GL resources
  if (gl_ == nullptr) {
    const int max_w = model_->vis.global.offwidth, max_h = model_->vis.global.offheight;
    std::unique_ptr<Gl> kept;
    if (GlContext::reuse_on()) {
      const std::lock_guard<std::mutex> lock(KeptGlMutex());
      kept = std::move(KeptGl());
    }
    if (kept != nullptr && backend_ == GlBackend::kOsMesa &&
        kept->model_signature == RenderSignature(model_) &&
        kept->context->max_width_px() == max_w && kept->context->max_height_px() == max_h) {
      gl_ = std::move(kept);
      took_kept_state_ = true;
    } else {
      Release(std::move(kept));  // its context (with its compiled shaders) is the one taken next
      gl_ = Gl::Create(model_, backend_, max_w, max_h);
    }
  }
  gl_->context->MakeCurrent();  // another renderer may have made its own current since
}

cv::Mat OffscreenRenderer::Render(mjData* data, int camera_id, int width_px, int height_px,
                                  bool show_tendons) {
  cv::Mat bgr;
  Render(data, camera_id, width_px, height_px, show_tendons, &bgr);
  return bgr;
}

void OffscreenRenderer::SetGeomCopies(int geom_id, std::vector<std::array<double, 3>> positions_W,
                                      std::vector<std::array<double, 3>> box_sizes_m) {
  copied_geom_ = geom_id;
  copy_positions_W_ = std::move(positions_W);
  copy_box_sizes_m_ = std::move(box_sizes_m);
}

// The copies SetGeomCopies asked for, after the scene's own geoms (as many as the scene holds).
void OffscreenRenderer::AddGeomCopies(mjvScene* scene) const {
  if (copy_positions_W_.empty()) return;
  const int n = scene->ngeom;
  for (int i = 0; i < n; ++i) {
    const mjvGeom& g = scene->geoms[i];
    if (g.objtype != mjOBJ_GEOM || g.objid != copied_geom_) continue;
    for (size_t c = 0; c < copy_positions_W_.size(); ++c) {
      if (scene->ngeom >= scene->maxgeom) return;
      mjvGeom& copy = scene->geoms[scene->ngeom++];
      copy = g;
      for (int k = 0; k < 3; ++k) copy.pos[k] = static_cast<float>(copy_positions_W_[c][k]);
      copy.segid = scene->ngeom - 1;
      // a level box of its own size in the geom's material
      if (c < copy_box_sizes_m_.size()) {
        const std::array<double, 3>& size_m = copy_box_sizes_m_[c];
        if (size_m[0] > 0.0 && size_m[1] > 0.0 && size_m[2] > 0.0) {
          copy.type = mjGEOM_BOX;
          copy.dataid = -1;
          for (int k = 0; k < 3; ++k) copy.size[k] = static_cast<float>(0.5 * size_m[k]);
          for (int k = 0; k < 9; ++k) copy.mat[k] = k % 4 == 0 ? 1.0f : 0.0f;
        }
      }
    }
    return;
  }
}

void OffscreenRenderer::Render(mjData* data, int camera_id, int width_px, int height_px,
                               bool show_tendons, cv::Mat* bgr, const cv::Rect& region) {
  CheckRenderRequest(model_, camera_id, width_px, height_px);
  Prepare();

  // scene from the current kinematics, seen from the fixed camera
  gl_->camera.type = mjCAMERA_FIXED;
  gl_->camera.fixedcamid = camera_id;
  for (int g = 0; g < mjNGROUP; ++g) {
    gl_->option.tendongroup[g] = show_tendons ? 1 : 0;
    gl_->option.geomgroup[g] = geom_group_visible_[g] ? 1 : 0;
  }
  mjv_updateScene(model_, data, &gl_->option, nullptr, &gl_->camera, mjCAT_ALL, &gl_->scene);
  AddGeomCopies(&gl_->scene);
  bgr->create(height_px, width_px, CV_8UC3);  // no allocation when the size is unchanged
  const cv::Rect frame(0, 0, width_px, height_px);
  const cv::Rect area = region.area() > 0 ? (region & frame) : frame;
  if (area.area() == 0) return;
  // only `area` of the frame: the frustum narrowed to it, so its pixels are the frame's
  if (area != frame) NarrowFrustumToArea(area, width_px, height_px, &gl_->scene);
  // what the frame cannot show is left out: no pixel changes, llvmpipe has fewer triangles
  last_culled_geoms_ =
      cull_hidden_geoms_
          ? CullHiddenGeoms(model_, static_cast<double>(area.width) / area.height, &gl_->scene)
          : 0;
  const mjrRect viewport = {0, 0, area.width, area.height};
  mjr_render(viewport, &gl_->scene, &gl_->render_context);
  cv::Mat out = (*bgr)(area);
  gl_->ReadPixels(viewport, width_px, &out, &flip_buffer_);
}

}  // namespace hpa::sim
