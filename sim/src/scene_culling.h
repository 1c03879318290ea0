#pragma once
// Culling of the geoms a frame cannot show, so that llvmpipe neither transforms nor sets up
// their triangles: those wholly outside the view frustum and those wholly hidden inside or
// behind an opaque sphere (the payload hides the slack cable's catenary below it). Every test
// is conservative, so the frame is the same pixel for pixel with or without it.

#include <mujoco/mujoco.h>

#include <array>
#include <optional>

namespace hpa::sim {

/// A convex hull of up to eight points grown by a radius, containing everything MuJoCo 2.2 draws
/// for one scene geom (its built-in meshes' vertices lie on the geom's surface).
struct GeomExtent {
  std::array<std::array<double, 3>, 8> points_W{};  // in the model frame
  int count = 0;                                    // 0: unknown extent, never culled
  double radius_m = 0.0;
};

/// The extent of a sphere, ellipsoid, capsule, cylinder or box geom of a scene; count 0 for any
/// other type (planes, meshes, height fields, lines, labels, skins).
GeomExtent ExtentOf(const mjvGeom& geom);

/// The view the scene's geoms are drawn in: the eye, its axes and the frustum at the near plane,
/// as mjr_render sets them for a viewport of width / height = aspect.
struct ViewFrustum {
  std::array<double, 3> eye_W{};                         // the eye in the model (world) frame
  std::array<double, 3> right_W{}, up_W{}, forward_W{};  // its unit axes; forward into the scene
  double near_left_m = 0, near_right_m = 0;              // the frustum's edges at the near plane
  double near_bottom_m = 0, near_top_m = 0;
  double near_m = 0, far_m = 0;  // clip distances along forward
};

/// The frustum mjr_render draws `scene` in (its mono camera, the average of both eyes) into a
/// viewport of the given aspect ratio (width / height).
ViewFrustum FrustumOf(const mjvScene& scene, double aspect);

/// True when nothing of `extent` lies inside `frustum` (by a margin).
bool OutsideFrustum(const GeomExtent& extent, const ViewFrustum& frustum);

/// An opaque sphere seen from the eye: the ball its drawn polyhedron surely contains.
struct Occluder {
  std::array<double, 3> centre_W{};
  double inner_radius_m = 0.0;  // inside the polyhedron MuJoCo draws
  int geom_index = -1;          // the occluding geom itself, never culled by itself
};

/// The ball the built-in sphere mesh (quality.numslices x numstacks) scaled by `geom` surely
/// contains, if `geom` is an opaque sphere or ellipsoid whose front the frustum shows whole.
std::optional<Occluder> OccluderOf(const mjvGeom& geom, int geom_index, const ViewFrustum& frustum,
                                   int numslices, int numstacks);

/// True when every point of `extent` is inside `occluder`'s ball, or lies behind it on a ray
/// from the eye that passes through the ball: no pixel can show it (the occluder is nearer).
bool HiddenBy(const GeomExtent& extent, const Occluder& occluder, const ViewFrustum& frustum);

/// Drops from `scene` the geoms a viewport of aspect width / height cannot show (outside the
/// frustum, or inside or behind an opaque sphere), keeping the others in their order; returns how
/// many it dropped. Does nothing with stereo, reflections, shadows, wireframe, segmentation or a
/// model transform (other views, or not filled surfaces).
int CullHiddenGeoms(const mjModel* model, double aspect, mjvScene* scene);

}  // namespace hpa::sim
