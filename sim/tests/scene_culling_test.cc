// Scene culling: every geom it drops is outside the frustum or hidden by an opaque sphere, checked
// by sampling the geoms' points against the frustum and rays from the eye; the ball it trusts
// inside a sphere lies inside MuJoCo's sphere mesh.

#include "sim/src/scene_culling.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <optional>
#include <random>

namespace hpa::sim {
namespace {

using Vec3 = std::array<double, 3>;

double Dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 Sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }

// A camera at (0, 0, 1) looking straight down (the payload camera's pose at hover), up = +y,
// with the payload camera's frustum (fovy 75 degrees, 16:9, near 1 cm, far 100 m).
mjvScene DownwardScene() {
  mjvScene scene{};
  mjvGLCamera cam{};
  cam.pos[2] = 1.0f;
  cam.forward[2] = -1.0f;
  cam.up[1] = 1.0f;
  cam.frustum_near = 0.01f;
  cam.frustum_far = 100.0f;
  const float half = 0.01f * std::tan(75.0f / 2.0f * static_cast<float>(M_PI) / 180.0f);
  cam.frustum_bottom = -half;
  cam.frustum_top = half;
  scene.camera[0] = cam;
  scene.camera[1] = cam;
  scene.stereo = mjSTEREO_NONE;
  return scene;
}

// A geom of `type` at `pos` with `size`, axes along the model's (a capsule along z).
mjvGeom MakeGeom(int type, const Vec3& pos, const Vec3& size, float alpha = 1.0f) {
  mjvGeom g{};
  g.type = type;
  for (int k = 0; k < 3; ++k) {
    g.pos[k] = static_cast<float>(pos[k]);
    g.size[k] = static_cast<float>(size[k]);
  }
  g.mat[0] = g.mat[4] = g.mat[8] = 1.0f;
  g.rgba[0] = g.rgba[3] = alpha;
  return g;
}

// Whether point p (model frame) projects inside the frustum: between the near and far planes and
// within the four side planes.
bool InsideFrustum(const Vec3& p, const ViewFrustum& f) {
  const Vec3 d = Sub(p, f.eye_W);
  const double x = Dot(d, f.right_W), y = Dot(d, f.up_W), z = Dot(d, f.forward_W);
  return z >= f.near_m && z <= f.far_m && x * f.near_m >= f.near_left_m * z &&
         x * f.near_m <= f.near_right_m * z && y * f.near_m >= f.near_bottom_m * z &&
         y * f.near_m <= f.near_top_m * z;
}

// Random points of the extent: on its hull's segment (or box) grown by its radius.
Vec3 SamplePoint(const GeomExtent& e, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> n(0.0, 1.0);
  Vec3 base = e.points_W[0];
  if (e.count == 2) {
    const double t = u(rng);
    for (int k = 0; k < 3; ++k) base[k] += t * (e.points_W[1][k] - e.points_W[0][k]);
  }
  Vec3 dir = {n(rng), n(rng), n(rng)};
  const double norm = std::sqrt(Dot(dir, dir));
  const double r = e.radius_m * std::cbrt(u(rng));
  for (int k = 0; k < 3; ++k) base[k] += r * dir[k] / norm;
  return base;
}

TEST(SceneCullingTest, DroppedGeomsHaveNoPointInTheFrustum) {
  const mjvScene scene = DownwardScene();
  const ViewFrustum f = FrustumOf(scene, 16.0 / 9.0);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> where(-1.5, 1.5), size(0.001, 0.3);
  int culled = 0, kept = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const int type = trial % 2 == 0 ? mjGEOM_SPHERE : mjGEOM_CAPSULE;
    const mjvGeom g = MakeGeom(type, {where(rng), where(rng), 1.0 + where(rng)},
                               {size(rng), size(rng), size(rng)});
    const GeomExtent e = ExtentOf(g);
    if (!OutsideFrustum(e, f)) {
      ++kept;
      continue;
    }
    ++culled;
    for (int s = 0; s < 200; ++s) ASSERT_FALSE(InsideFrustum(SamplePoint(e, rng), f)) << trial;
  }
  // both outcomes occur: the test samples both sides
  EXPECT_GT(culled, 400);
  EXPECT_GT(kept, 400);
}

TEST(SceneCullingTest, KnownGeomsAroundTheCamera) {
  const mjvScene scene = DownwardScene();
  const ViewFrustum f = FrustumOf(scene, 16.0 / 9.0);
  // the quadrotor's box around and behind the camera (camera 5 cm below its centre): behind
  EXPECT_TRUE(OutsideFrustum(ExtentOf(MakeGeom(mjGEOM_BOX, {0, 0, 1.05}, {0.1, 0.1, 0.03})), f));
  // a box whose lower face is 1 mm in front of the near plane is kept
  EXPECT_FALSE(OutsideFrustum(ExtentOf(MakeGeom(mjGEOM_BOX, {0, 0, 1.019}, {0.1, 0.1, 0.03})), f));
  // the payload 0.5 m below: kept; 1 m to the side of the view at that depth: dropped
  EXPECT_FALSE(
      OutsideFrustum(ExtentOf(MakeGeom(mjGEOM_SPHERE, {0, 0, 0.5}, {0.04, 0.04, 0.04})), f));
  EXPECT_TRUE(
      OutsideFrustum(ExtentOf(MakeGeom(mjGEOM_SPHERE, {1.0, 0, 0.5}, {0.04, 0.04, 0.04})), f));
  // a plane is never dropped (its extent is unknown to culling)
  EXPECT_FALSE(OutsideFrustum(ExtentOf(MakeGeom(mjGEOM_PLANE, {0, 0, 5}, {10, 10, 1})), f));
}

// The cone through a ball from the eye, and the ray test the culling must agree with: p is hidden
// when it is in the ball or the ray to it enters the ball before reaching it.
bool RayHidden(const Vec3& p, const Vec3& eye, const Vec3& centre, double radius) {
  const Vec3 d = Sub(p, eye);
  const double length = std::sqrt(Dot(d, d));
  const Vec3 u = {d[0] / length, d[1] / length, d[2] / length};
  const Vec3 oc = Sub(centre, eye);
  const double along = Dot(oc, u);
  const double miss2 = Dot(oc, oc) - along * along;
  if (miss2 > radius * radius) return false;
  const double entry = along - std::sqrt(radius * radius - miss2);
  return entry < length;
}

TEST(SceneCullingTest, HiddenGeomsAreBehindOrInsideTheOccluder) {
  const mjvScene scene = DownwardScene();
  const ViewFrustum f = FrustumOf(scene, 16.0 / 9.0);
  // the payload 0.25 m below the camera (a slack cable), 4 cm ball
  const mjvGeom payload = MakeGeom(mjGEOM_SPHERE, {0.02, 0.01, 0.75}, {0.04, 0.04, 0.04});
  const std::optional<Occluder> occluder = OccluderOf(payload, 0, f, 28, 16);
  ASSERT_TRUE(occluder.has_value());
  const Occluder& o = *occluder;
  ASSERT_GT(o.inner_radius_m, 0.9 * 0.04);
  ASSERT_LT(o.inner_radius_m, 0.04);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> xy(-0.08, 0.08), z(0.3, 0.9), half(0.0, 0.1);
  int hidden = 0, shown = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    mjvGeom g = MakeGeom(mjGEOM_CAPSULE, {xy(rng), xy(rng), z(rng)}, {0.002, 0.002, half(rng)});
    // a random direction for the capsule's axis (mat's third column)
    std::normal_distribution<double> n(0.0, 1.0);
    Vec3 a = {n(rng), n(rng), n(rng)};
    const double norm = std::sqrt(Dot(a, a));
    g.mat[2] = static_cast<float>(a[0] / norm);
    g.mat[5] = static_cast<float>(a[1] / norm);
    g.mat[8] = static_cast<float>(a[2] / norm);
    const GeomExtent e = ExtentOf(g);
    if (!HiddenBy(e, o, f)) {
      ++shown;
      continue;
    }
    ++hidden;
    for (int s = 0; s < 50; ++s) {
      ASSERT_TRUE(RayHidden(SamplePoint(e, rng), f.eye_W, o.centre_W, o.inner_radius_m)) << trial;
    }
  }
  EXPECT_GT(hidden, 500);
  EXPECT_GT(shown, 500);
  // the cable's site at the payload's centre and the cable hanging straight below it: hidden
  EXPECT_TRUE(
      HiddenBy(ExtentOf(MakeGeom(mjGEOM_SPHERE, {0.02, 0.01, 0.75}, {0.005, 0.005, 0.005})), o, f));
  EXPECT_TRUE(
      HiddenBy(ExtentOf(MakeGeom(mjGEOM_CAPSULE, {0.02, 0.01, 0.6}, {0.002, 0.002, 0.1})), o, f));
  // the cable from the camera down to the payload's top: in front of it, shown
  EXPECT_FALSE(
      HiddenBy(ExtentOf(MakeGeom(mjGEOM_CAPSULE, {0.01, 0.005, 0.87}, {0.002, 0.002, 0.1})), o, f));
}

TEST(SceneCullingTest, OnlyOpaqueSpheresWithTheirFrontInViewOcclude) {
  const mjvScene scene = DownwardScene();
  const ViewFrustum f = FrustumOf(scene, 16.0 / 9.0);
  const auto occludes = [&](const mjvGeom& g) { return OccluderOf(g, 0, f, 28, 16).has_value(); };
  EXPECT_TRUE(occludes(MakeGeom(mjGEOM_SPHERE, {0, 0, 0.5}, {0.04, 0.04, 0.04})));
  EXPECT_FALSE(
      occludes(MakeGeom(mjGEOM_SPHERE, {0, 0, 0.5}, {0.04, 0.04, 0.04}, 0.5f)));  // blended
  EXPECT_FALSE(occludes(MakeGeom(mjGEOM_BOX, {0, 0, 0.5}, {0.04, 0.04, 0.04})));
  // cut by the near plane (its front 5 mm from the eye)
  EXPECT_FALSE(occludes(MakeGeom(mjGEOM_SPHERE, {0, 0, 0.955}, {0.04, 0.04, 0.04})));
}

// MuJoCo 2.2's unit sphere mesh (render_context.c, sphere()): rings at elevations
// (pi/2) k / (numstacks/2), numslices vertices each, poles closed by triangles. Each face's plane
// lies at least the occluder's inner radius (before its 1 % rasterisation margin) from the centre.
TEST(SceneCullingTest, InnerBallLiesInsideMujocosSphereMesh) {
  for (const auto& tessellation : {std::pair{28, 16}, std::pair{8, 6}, std::pair{64, 32}}) {
    const int slices = tessellation.first, stacks = tessellation.second;
    const mjvScene scene = DownwardScene();
    const ViewFrustum f = FrustumOf(scene, 1.0);
    const std::optional<Occluder> o =
        OccluderOf(MakeGeom(mjGEOM_SPHERE, {0, 0, 0.5}, {1e-2, 1e-2, 1e-2}), 0, f, slices, stacks);
    ASSERT_TRUE(o.has_value());
    const double inner = o->inner_radius_m / 1e-2 / 0.99;
    const int half = stacks / 2;
    const auto vertex = [&](int ring, int j) {
      const double el = M_PI / 2 * ring / half, az = 2 * M_PI * j / slices;
      return Vec3{std::cos(az) * std::cos(el), std::sin(az) * std::cos(el), std::sin(el)};
    };
    double closest = 1.0;
    for (int ring = -half; ring < half; ++ring) {
      for (int j = 0; j < slices; ++j) {
        // the face's three distinct corners (a pole's triangle has only three)
        const Vec3 a = vertex(ring, j), b = vertex(ring + 1, j + 1);
        const Vec3 c = ring + 1 == half ? vertex(ring, j + 1) : vertex(ring + 1, j);
        const Vec3 ab = Sub(b, a), ac = Sub(c, a);
        Vec3 normal = {ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2],
                       ab[0] * ac[1] - ab[1] * ac[0]};
        const double norm = std::sqrt(Dot(normal, normal));
        if (norm < 1e-12) continue;
        closest = std::min(closest, std::fabs(Dot(normal, a)) / norm);
      }
    }
    EXPECT_LE(inner, closest) << slices << "x" << stacks;
    // not needlessly small: the bound adds half a stack to half a slice, loosest on coarse meshes
    EXPECT_GT(inner, closest - 0.15) << slices << "x" << stacks;
  }
}

}  // namespace
}  // namespace hpa::sim
