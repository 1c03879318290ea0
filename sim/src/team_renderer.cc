// TeamRenderer: the team video's cameras, drawn from a render-only copy of the team's scene.

#include "hpa/sim/team_renderer.h"

#include <mujoco/mujoco.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <string>

#include "hpa/models/cooperative_model.h"
#include "hpa/models/rotor_model.h"
#include "hpa/sim/team_world.h"
#include "offscreen_renderer.h"
#include "world_detail.h"

namespace hpa::sim {
namespace {

constexpr double kChaseFovy_deg = 50.0;
constexpr double kChaseElevation_rad = 25.0 * M_PI / 180.0;  // looking down at the team's centre
// turned from straight behind (-y) towards +x, so that vehicles side by side along y do not hide
// each other, nor does a triangle's vehicle at -x -y hide the payload
constexpr double kChaseAzimuth_rad = 25.0 * M_PI / 180.0;
// room around the hanging team for its motion (a swing, a slack cable, a manoeuvre) (m)
constexpr double kChaseMargin_m = 0.4;
constexpr double kChaseCableWidth_m = 0.006;  // cables thick enough to see from the chase camera

// Each vehicle's rotor disc colour (RGB, 0..1): no red, which is the payload's.
constexpr std::array<std::array<double, 3>, 3> kVehicleRgb = {
    {{0.2, 0.45, 0.95}, {0.2, 0.8, 0.3}, {0.95, 0.8, 0.1}}};

// "x y z" of a vector.
std::string Triple(const Eigen::Vector3d& v) {
  std::ostringstream out;
  out << std::setprecision(17) << v.x() << ' ' << v.y() << ' ' << v.z();
  return out.str();
}

// "w x y z" of a rotation.
std::string Quat(const Eigen::Matrix3d& R) {
  const Eigen::Quaterniond q(R);
  std::ostringstream out;
  out << std::setprecision(17) << q.w() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z();
  return out.str();
}

// Inserts `text` before the first `marker` in xml (after it with after = true, at the end of
// its line); the scene is generated, so a missing marker is a bug.
void Insert(std::string* xml, const std::string& marker, const std::string& text, bool after) {
  size_t at = xml->find(marker);
  if (at == std::string::npos) {
    throw std::logic_error("the team's scene has no '" + marker + "' to render from");
  }
  if (after) at = xml->find('\n', at) + 1;
  xml->insert(at, text);
}

// The team's MJCF with what only the pictures need: a checker floor, a light, each vehicle's
// rotor discs and onboard camera "onboard_<i>", and the chase camera "team_chase" (posed per
// frame). Nothing here has mass or collides; the bodies and joints are the physics scene's, so
// its qpos poses this one.
std::string RenderSceneXml(std::string xml, const CooperativeTeam& team) {
  Insert(&xml, "  <worldbody>",
         "  <visual>\n"
         "    <global offwidth=\"" +
             std::to_string(TeamRenderer::kMaxWidthPx) + "\" offheight=\"" +
             std::to_string(TeamRenderer::kMaxHeightPx) + "\"/>\n" +
             "    <quality shadowsize=\"0\" offsamples=\"0\"/>\n"
             "    <headlight ambient=\"0.4 0.4 0.4\" diffuse=\"0.6 0.6 0.6\" specular=\"0 0 0\"/>\n"
             "  </visual>\n"
             "  <asset>\n"
             "    <texture name=\"hpa_floor_tex\" type=\"2d\" builtin=\"checker\" "
             "rgb1=\"0.45 0.45 0.45\" rgb2=\"0.3 0.3 0.3\" width=\"256\" height=\"256\"/>\n"
             "    <material name=\"hpa_floor\" texture=\"hpa_floor_tex\" texrepeat=\"20 20\" "
             "reflectance=\"0\"/>\n"
             "  </asset>\n",
         false);
  Insert(&xml, "<geom name=\"ground\"", "<geom material=\"hpa_floor\" ", false);
  xml.erase(xml.find("<geom name=\"ground\""), std::strlen("<geom "));
  const int n = static_cast<int>(team.vehicles.size());
  for (int i = 0; i < n; ++i) {
    const Params& p = team.vehicles[i].params;
    const std::array<double, 3>& rgb = kVehicleRgb[i % kVehicleRgb.size()];
    std::ostringstream extra;
    extra << std::setprecision(17);
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d r_B = RotorPosition_B(p, k);
      const Eigen::Vector3d disc_B(r_B.x(), r_B.y(), p.body_half_size_m.z() + 0.005);
      extra << "      <geom type=\"cylinder\" size=\"" << 0.4 * r_B.head<2>().norm()
            << " 0.004\" pos=\"" << Triple(disc_B) << "\" rgba=\"" << rgb[0] << ' ' << rgb[1] << ' '
            << rgb[2] << " 0.8\" contype=\"0\" conaffinity=\"0\" group=\"1\"/>\n";
    }
    // MuJoCo's camera looks along its -z with image up +y: R_B,mjcam = R_BC * diag(1, -1, -1)
    // with C OpenCV's (the single world's payload camera, world_params.cc)
    const Eigen::Matrix3d R_B_mjcam = p.R_BC * Eigen::Vector3d(1, -1, -1).asDiagonal();
    extra << "      <camera name=\"onboard_" << i << "\" pos=\"" << Triple(p.t_BC_B_m)
          << "\" quat=\"" << Quat(R_B_mjcam) << "\" fovy=\"" << p.camera_fovy_deg << "\"/>\n";
    Insert(&xml, "<site name=\"cable_quadrotor_" + std::to_string(i) + "\"", extra.str(), true);
  }
  Insert(&xml, "  </worldbody>",
         "    <light directional=\"true\" castshadow=\"false\" pos=\"0 0 10\" "
         "dir=\"0.3 0.2 -1\" diffuse=\"0.5 0.5 0.5\"/>\n"
         "    <camera name=\"team_chase\" pos=\"0 -3 2\" fovy=\"" +
             std::to_string(kChaseFovy_deg) + "\"/>\n",
         false);
  return xml;
}

// Compiles MJCF text through MuJoCo's virtual file system.
mjModel* CompileXml(const std::string& xml, std::string* error) {
  const char* kName = "hpa_team_render_scene.xml";
  auto vfs = std::make_unique<mjVFS>();  // about 2 MB of fixed tables: not on the stack
  mj_defaultVFS(vfs.get());
  if (mj_makeEmptyFileVFS(vfs.get(), kName, static_cast<int>(xml.size())) != 0) {
    *error = "cannot make the in-memory file";
    return nullptr;
  }
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), kName)], xml.data(), xml.size());
  char text[1024] = "";
  mjModel* m = mj_loadXML(kName, vfs.get(), text, sizeof(text));
  mj_deleteVFS(vfs.get());
  *error = text;
  return m;
}

}  // namespace

struct TeamRenderer::Impl {
  const TeamWorld& world;
  int n = 0;
  mjModel* m = nullptr;  // the render-only scene
  mjData* d = nullptr;   // posed from the world's qpos before each frame
  std::unique_ptr<OffscreenRenderer> offscreen;
  int chase_camera = -1, payload_body = -1;
  std::vector<int> onboard_camera, cable_tendon;  // (n)
  std::vector<int> strut_geoms;                   // the payload's visual struts (0 .. n)
  std::vector<std::array<float, 4>> strut_rgba;   // their colours in the video (as strut_geoms)
  std::vector<double> onboard_fovy_deg;           // the onboard cameras' fovy in the video  (n)
  double chase_distance_m = 3.0;                  // from the team's centre
  float cable_width_m = 0.002f;                   // the scene's own width

  explicit Impl(const TeamWorld& w) : world(w) {}

  ~Impl() {
    offscreen.reset();
    if (d != nullptr) mj_deleteData(d);
    if (m != nullptr) mj_deleteModel(m);
  }

  // this instant's poses, cable paths and camera placements from the world's state (read only)
  void Pose() {
    const mjData* wd = world.data();
    mju_copy(d->qpos, wd->qpos, m->nq);
    d->time = wd->time;
    mj_kinematics(m, d);
    mj_comPos(m, d);

    // the chase camera behind and above the mean of the bodies' positions
    Eigen::Vector3d centre_W = Eigen::Vector3d::Zero();
    centre_W += Eigen::Map<const Eigen::Vector3d>(d->xpos + 3 * payload_body);
    for (int i = 0; i < n; ++i) {
      const int b = m->cam_bodyid[onboard_camera[i]];
      centre_W += Eigen::Map<const Eigen::Vector3d>(d->xpos + 3 * b);
    }
    centre_W /= n + 1;
    if (!centre_W.allFinite()) centre_W.setZero();
    const Eigen::Vector3d back_W(std::sin(kChaseAzimuth_rad) * std::cos(kChaseElevation_rad),
                                 -std::cos(kChaseAzimuth_rad) * std::cos(kChaseElevation_rad),
                                 std::sin(kChaseElevation_rad));
    const Eigen::Vector3d p_WC_W = centre_W + chase_distance_m * back_W;
    // MuJoCo camera axes: x right, y up, z back (it looks along -z)
    const Eigen::Vector3d z_W = back_W;
    const Eigen::Vector3d x_W = Eigen::Vector3d::UnitZ().cross(z_W).normalized();
    Eigen::Matrix3d R_WC;
    R_WC << x_W, z_W.cross(x_W), z_W;
    const Eigen::Quaterniond q_WC(R_WC);
    for (int k = 0; k < 3; ++k) m->cam_pos[3 * chase_camera + k] = p_WC_W(k);
    m->cam_quat[4 * chase_camera + 0] = q_WC.w();
    m->cam_quat[4 * chase_camera + 1] = q_WC.x();
    m->cam_quat[4 * chase_camera + 2] = q_WC.y();
    m->cam_quat[4 * chase_camera + 3] = q_WC.z();

    // a slack cable in orange, a taut one dark grey
    const TeamTruth truth = world.GetTruth();
    for (int i = 0; i < n; ++i) {
      const bool slack = truth.modes[i] == CableMode::kSlack;
      float* rgba = m->tendon_rgba + 4 * cable_tendon[i];
      rgba[0] = slack ? 1.0f : 0.1f;
      rgba[1] = slack ? 0.55f : 0.1f;
      rgba[2] = slack ? 0.0f : 0.1f;
    }
    mj_camlight(m, d);
    mj_tendon(m, d);
  }

  // every cable's drawn width
  void SetCableWidth(double width_m) {
    for (int i = 0; i < n; ++i) m->tendon_width[cable_tendon[i]] = width_m;
  }

  // the payload camera's look: vehicle's camera at fovy_deg, the struts in the vehicles' grey
  void SetPayloadCameraLook(int vehicle, double fovy_deg) {
    constexpr std::array<float, 4> kVehicleGreyRgba = {0.15f, 0.15f, 0.18f, 1.0f};
    m->cam_fovy[onboard_camera[vehicle]] = fovy_deg;
    for (int g : strut_geoms) {
      std::copy(kVehicleGreyRgba.begin(), kVehicleGreyRgba.end(), m->geom_rgba + 4 * g);
    }
  }

  // the video's look back: every onboard camera's own fovy, the struts' own colours
  void SetVideoLook() {
    for (int i = 0; i < n; ++i) m->cam_fovy[onboard_camera[i]] = onboard_fovy_deg[i];
    for (size_t k = 0; k < strut_geoms.size(); ++k) {
      std::copy(strut_rgba[k].begin(), strut_rgba[k].end(), m->geom_rgba + 4 * strut_geoms[k]);
    }
  }
};

TeamRenderer::TeamRenderer(const TeamWorld& world) : impl_(std::make_unique<Impl>(world)) {
  Impl& r = *impl_;
  const CooperativeTeam& team = world.team();
  r.n = world.VehicleCount();

  // the render-only scene; its load warnings are its own, not the world's
  InstallWarningHandler();
  TakeWarnings();
  std::string error;
  r.m = CompileXml(RenderSceneXml(world.scene_xml(), team), &error);
  TakeWarnings();
  if (r.m == nullptr) {
    throw std::runtime_error("MuJoCo cannot compile the team's render scene: " + error);
  }
  if (r.m->nq != world.model()->nq) {
    throw std::logic_error("the team's render scene has another qpos layout than its world's");
  }
  r.d = mj_makeData(r.m);
  // near and far planes (fractions of the extent): 1 cm, 60 m
  r.m->vis.map.znear = static_cast<float>(0.01 / r.m->stat.extent);
  r.m->vis.map.zfar = static_cast<float>(60.0 / r.m->stat.extent);
  r.chase_camera = mj_name2id(r.m, mjOBJ_CAMERA, "team_chase");
  r.payload_body = mj_name2id(r.m, mjOBJ_BODY, "payload");
  for (int i = 0; i < r.n; ++i) {
    const std::string s = std::to_string(i);
    r.onboard_camera.push_back(mj_name2id(r.m, mjOBJ_CAMERA, ("onboard_" + s).c_str()));
    r.cable_tendon.push_back(mj_name2id(r.m, mjOBJ_TENDON, ("cable_" + s).c_str()));
  }
  r.cable_width_m = static_cast<float>(r.m->tendon_width[r.cable_tendon.front()]);
  // the payload's struts: its geoms other than the ball (visual only)
  const int ball = mj_name2id(r.m, mjOBJ_GEOM, "payload_sphere");
  for (int g = 0; g < r.m->ngeom; ++g) {
    if (r.m->geom_bodyid[g] != r.payload_body || g == ball) continue;
    r.strut_geoms.push_back(g);
    const float* rgba = r.m->geom_rgba + 4 * g;
    r.strut_rgba.push_back({rgba[0], rgba[1], rgba[2], rgba[3]});
  }
  for (int i = 0; i < r.n; ++i) r.onboard_fovy_deg.push_back(r.m->cam_fovy[r.onboard_camera[i]]);

  // the chase distance: the hanging team's farthest body from its centre, plus room to move,
  // inside the vertical field of view
  const Eigen::VectorXd x = CooperativeModel(team).HangingState(Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> p_W;
  p_W.push_back(x.segment<3>(0));
  for (int i = 0; i < r.n; ++i) p_W.push_back(x.segment<3>(CooperativeStateIndex::Vehicle(i)));
  Eigen::Vector3d centre_W = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : p_W) centre_W += p;
  centre_W /= static_cast<double>(p_W.size());
  double radius_m = 0.0;
  for (const Eigen::Vector3d& p : p_W) radius_m = std::max(radius_m, (p - centre_W).norm());
  radius_m += kChaseMargin_m;
  r.chase_distance_m = radius_m / std::sin(0.5 * kChaseFovy_deg * M_PI / 180.0);
  r.offscreen = std::make_unique<OffscreenRenderer>(r.m, world.gl_backend());
}

TeamRenderer::~TeamRenderer() = default;

void TeamRenderer::RenderChaseCamera(int width_px, int height_px, cv::Mat* bgr) {
  const auto t0 = std::chrono::steady_clock::now();
  Impl& r = *impl_;
  r.Pose();
  r.SetCableWidth(kChaseCableWidth_m);
  r.offscreen->Render(r.d, r.chase_camera, width_px, height_px, true, bgr);
  r.SetCableWidth(r.cable_width_m);
  last_render_ms_ =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

cv::Mat TeamRenderer::RenderChaseCamera(int width_px, int height_px) {
  cv::Mat bgr;
  RenderChaseCamera(width_px, height_px, &bgr);
  return bgr;
}

void TeamRenderer::RenderOnboardCamera(int vehicle, int width_px, int height_px, cv::Mat* bgr) {
  Impl& r = *impl_;
  if (vehicle < 0 || vehicle >= r.n) {
    throw std::out_of_range("TeamRenderer::RenderOnboardCamera: no vehicle " +
                            std::to_string(vehicle));
  }
  const auto t0 = std::chrono::steady_clock::now();
  r.Pose();
  r.offscreen->Render(r.d, r.onboard_camera[vehicle], width_px, height_px, true, bgr);
  last_render_ms_ =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

cv::Mat TeamRenderer::RenderOnboardCamera(int vehicle) {
  cv::Mat bgr;
  RenderOnboardCamera(vehicle, kOnboardWidthPx, kOnboardHeightPx, &bgr);
  return bgr;
}

void TeamRenderer::RenderOnboardCamera(int vehicle, int width_px, int height_px, double fovy_deg,
                                       bool show_cables, cv::Mat* bgr) {
  Impl& r = *impl_;
  if (vehicle < 0 || vehicle >= r.n) {
    throw std::out_of_range("TeamRenderer::RenderOnboardCamera: no vehicle " +
                            std::to_string(vehicle));
  }
  if (!(fovy_deg > 0.0 && fovy_deg < 180.0)) {
    throw std::invalid_argument("TeamRenderer::RenderOnboardCamera: fovy " +
                                std::to_string(fovy_deg) + " deg is not in (0, 180)");
  }
  const auto t0 = std::chrono::steady_clock::now();
  r.Pose();
  r.SetPayloadCameraLook(vehicle, fovy_deg);
  try {
    r.offscreen->Render(r.d, r.onboard_camera[vehicle], width_px, height_px, show_cables, bgr);
  } catch (...) {
    r.SetVideoLook();
    throw;
  }
  r.SetVideoLook();
  last_render_ms_ =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

cv::Scalar TeamRenderer::VehicleColorBgr(int vehicle) const {
  const std::array<double, 3>& rgb =
      kVehicleRgb[static_cast<size_t>(std::max(vehicle, 0)) % kVehicleRgb.size()];
  return cv::Scalar(255.0 * rgb[2], 255.0 * rgb[1], 255.0 * rgb[0]);
}

}  // namespace hpa::sim
