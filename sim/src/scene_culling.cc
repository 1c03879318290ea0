#include "scene_culling.h"

#include <algorithm>
#include <cmath>

namespace hpa::sim {
namespace {

using Vec3 = std::array<double, 3>;

double Dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 Sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 Cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
Vec3 Normalized(const Vec3& a) {
  const double n = std::sqrt(Dot(a, a));
  return n > 0.0 ? Vec3{a[0] / n, a[1] / n, a[2] / n} : a;
}
Vec3 FromFloat(const float* v) { return {v[0], v[1], v[2]}; }

// A geom's local axis k (0..2) in the model frame: mjvGeom::mat is row-major, axes in columns.
Vec3 Axis(const mjvGeom& geom, int k) { return {geom.mat[k], geom.mat[3 + k], geom.mat[6 + k]}; }

// Slack added to every distance a test compares, far above float rounding in the scene and far
// below a pixel at any distance the camera renders.
constexpr double kMarginM = 1e-6;

// The point `extent`'s point i in the eye's frame (x right, y up, z into the scene).
Vec3 InEye(const Vec3& p, const ViewFrustum& f) {
  const Vec3 d = Sub(p, f.eye_W);
  return {Dot(d, f.right_W), Dot(d, f.up_W), Dot(d, f.forward_W)};
}

}  // namespace

GeomExtent ExtentOf(const mjvGeom& geom) {
  GeomExtent e;
  const Vec3 pos = FromFloat(geom.pos);
  const double s0 = geom.size[0], s1 = geom.size[1], s2 = geom.size[2];
  const auto along = [&](const Vec3& axis, double t) {
    return Vec3{pos[0] + t * axis[0], pos[1] + t * axis[1], pos[2] + t * axis[2]};
  };
  switch (geom.type) {
    case mjGEOM_SPHERE:
    case mjGEOM_ELLIPSOID:  // the unit sphere scaled by size
      e.points_W[0] = pos;
      e.count = 1;
      e.radius_m = std::max({s0, s1, s2});
      break;
    case mjGEOM_CAPSULE:   // cylinder of half-length size[2] with hemispherical ends
    case mjGEOM_CYLINDER:  // inside the capsule of its radius and half-length
      e.points_W[0] = along(Axis(geom, 2), -s2);
      e.points_W[1] = along(Axis(geom, 2), s2);
      e.count = 2;
      e.radius_m = std::max(s0, s1);
      break;
    case mjGEOM_BOX: {
      const Vec3 x = Axis(geom, 0), y = Axis(geom, 1), z = Axis(geom, 2);
      for (int i = 0; i < 8; ++i) {
        const double a = (i & 1) ? s0 : -s0, b = (i & 2) ? s1 : -s1, c = (i & 4) ? s2 : -s2;
        e.points_W[i] = {pos[0] + a * x[0] + b * y[0] + c * z[0],
                         pos[1] + a * x[1] + b * y[1] + c * z[1],
                         pos[2] + a * x[2] + b * y[2] + c * z[2]};
      }
      e.count = 8;
      break;
    }
    default:  // planes, meshes, height fields, arrows, lines, labels, skins: kept
      break;
  }
  e.radius_m += kMarginM;
  return e;
}

ViewFrustum FrustumOf(const mjvScene& scene, double aspect) {
  const mjvGLCamera cam = mjv_averageCamera(scene.camera, scene.camera + 1);
  ViewFrustum f;
  // mjr_lookAt's axes
  f.eye_W = FromFloat(cam.pos);
  f.forward_W = Normalized(FromFloat(cam.forward));
  f.right_W = Normalized(Cross(f.forward_W, FromFloat(cam.up)));
  f.up_W = Normalized(Cross(f.right_W, f.forward_W));
  // setView's frustum: the width follows the viewport's aspect ratio
  const double half_width = 0.5 * aspect * (cam.frustum_top - cam.frustum_bottom);
  f.near_left_m = cam.frustum_center - half_width;
  f.near_right_m = cam.frustum_center + half_width;
  f.near_bottom_m = cam.frustum_bottom;
  f.near_top_m = cam.frustum_top;
  f.near_m = cam.frustum_near;
  f.far_m = cam.frustum_far;
  return f;
}

bool OutsideFrustum(const GeomExtent& extent, const ViewFrustum& f) {
  if (extent.count == 0) return false;
  // inward normals (x, y, z in the eye frame, unnormalised) and offsets of the six planes:
  // inside when n . p + offset >= 0
  const double n = f.near_m;
  const double planes[6][4] = {
      {0, 0, 1, -f.near_m},       {0, 0, -1, f.far_m},         {n, 0, -f.near_left_m, 0},
      {-n, 0, f.near_right_m, 0}, {0, n, -f.near_bottom_m, 0}, {0, -n, f.near_top_m, 0},
  };
  for (const auto& plane : planes) {
    const double norm = std::sqrt(plane[0] * plane[0] + plane[1] * plane[1] + plane[2] * plane[2]);
    bool all_outside = true;
    for (int i = 0; i < extent.count && all_outside; ++i) {
      const Vec3 p = InEye(extent.points_W[i], f);
      const double distance =
          (plane[0] * p[0] + plane[1] * p[1] + plane[2] * p[2] + plane[3]) / norm;
      all_outside = distance < -(extent.radius_m + kMarginM);
    }
    if (all_outside) return true;
  }
  return false;
}

std::optional<Occluder> OccluderOf(const mjvGeom& geom, int geom_index, const ViewFrustum& f,
                                   int numslices, int numstacks) {
  if (geom.type != mjGEOM_SPHERE && geom.type != mjGEOM_ELLIPSOID) return std::nullopt;
  if (!(geom.rgba[3] >= 0.995f) || geom.label[0] != 0)
    return std::nullopt;  // mjr_render blends below
  if (numslices < 3 || numstacks < 2) return std::nullopt;
  // every face of the unit UV sphere (numstacks / 2 stacks a hemisphere) has its vertices within
  // half a stack plus half a slice of its centre direction c, so each of its points p has
  // p . c >= cos of that: the mesh holds the ball of that radius; 1 % less for rasterisation
  const double half_stack = 0.5 * M_PI / std::max(1, numstacks / 2) / 2.0;
  const double half_slice = M_PI / numslices;
  const double inner = 0.99 * std::cos(half_stack + half_slice);
  if (!(inner > 0.0)) return std::nullopt;
  const double outer = std::max({geom.size[0], geom.size[1], geom.size[2]});
  const Vec3 centre = FromFloat(geom.pos);
  const Vec3 c = InEye(centre, f);
  // the front must be drawn whole: the eye outside, nothing of it cut by the near or far plane
  if (std::sqrt(Dot(c, c)) <= outer || c[2] - outer <= f.near_m + kMarginM ||
      c[2] + outer >= f.far_m - kMarginM) {
    return std::nullopt;
  }
  Occluder o;
  o.centre_W = centre;
  o.inner_radius_m = inner * std::min({geom.size[0], geom.size[1], geom.size[2]});
  o.geom_index = geom_index;
  return o;
}

bool HiddenBy(const GeomExtent& extent, const Occluder& o, const ViewFrustum& f) {
  if (extent.count == 0) return false;
  const double rho = o.inner_radius_m, w = extent.radius_m;
  // inside the ball: the ray to each point enters the occluder's mesh first
  bool inside = true;
  for (int i = 0; i < extent.count && inside; ++i) {
    const Vec3 d = Sub(extent.points_W[i], o.centre_W);
    inside = std::sqrt(Dot(d, d)) + w <= rho - kMarginM;
  }
  if (inside) return true;
  // behind it: inside the cone of rays through the ball and beyond the plane of the circle
  // where the cone touches it (the side of the ball the eye sees lies before that plane), a
  // convex set, so the points' hull is in it when each point's ball of radius w is
  const Vec3 to_centre = Sub(o.centre_W, f.eye_W);
  const double distance = std::sqrt(Dot(to_centre, to_centre));
  if (!(distance > rho)) return false;
  const Vec3 axis = {to_centre[0] / distance, to_centre[1] / distance, to_centre[2] / distance};
  const double cone_half_angle = std::asin(rho / distance);
  const double touch_plane_m = (distance * distance - rho * rho) / distance;
  for (int i = 0; i < extent.count; ++i) {
    const Vec3 v = Sub(extent.points_W[i], f.eye_W);
    const double along = Dot(v, axis), length = std::sqrt(Dot(v, v));
    if (along < touch_plane_m + w + kMarginM || length <= w) return false;
    const double angle = std::acos(std::clamp(along / length, -1.0, 1.0));
    if (angle + std::asin(std::min(1.0, w / length)) > cone_half_angle - 1e-9) return false;
  }
  return true;
}

int CullHiddenGeoms(const mjModel* model, double aspect, mjvScene* scene) {
  // stereo draws two views, reflections a mirrored scene and shadows light views: the frustum
  // is not the only one; wireframe and segmentation draw outlines or flat colours
  if (scene->stereo != mjSTEREO_NONE || scene->enabletransform || scene->flags[mjRND_WIREFRAME] ||
      scene->flags[mjRND_SEGMENT] || scene->flags[mjRND_REFLECTION] || scene->flags[mjRND_SHADOW] ||
      !(aspect > 0.0)) {
    return 0;
  }
  const ViewFrustum f = FrustumOf(*scene, aspect);
  // the first few opaque spheres occlude (fewer occluders only cull less)
  std::array<Occluder, 8> occluders;
  size_t occluder_count = 0;
  for (int i = 0; i < scene->ngeom && occluder_count < occluders.size(); ++i) {
    const std::optional<Occluder> o = OccluderOf(
        scene->geoms[i], i, f, model->vis.quality.numslices, model->vis.quality.numstacks);
    if (o) occluders[occluder_count++] = *o;
  }
  int kept = 0;
  for (int i = 0; i < scene->ngeom; ++i) {
    const mjvGeom& geom = scene->geoms[i];
    bool hidden = false;
    if (geom.label[0] == 0) {  // a label is drawn beside its geom's place
      const GeomExtent extent = ExtentOf(geom);
      hidden = OutsideFrustum(extent, f);
      for (size_t k = 0; k < occluder_count && !hidden; ++k) {
        hidden = occluders[k].geom_index != i && HiddenBy(extent, occluders[k], f);
      }
    }
    if (!hidden) {
      if (kept != i) scene->geoms[kept] = geom;
      ++kept;
    }
  }
  const int dropped = scene->ngeom - kept;
  scene->ngeom = kept;
  return dropped;
}

}  // namespace hpa::sim
