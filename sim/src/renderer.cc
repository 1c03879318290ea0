// The rendered cameras: appearance randomisation, the payload camera with its image model and
// motion blur, the chase camera.

#include "hpa/sim/renderer.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <opencv2/imgproc.hpp>
#include <string>

#include "gl_context.h"
#include "hpa/models/input_error.h"
#include "hpa/models/seed_streams.h"
#include "hpa/sim/camera_image_model.h"
#include "hpa/sim/world.h"
#include "offscreen_renderer.h"
#include "world_detail.h"

namespace hpa::sim {

Renderer::Renderer(World& world) : w_(world) {
  if (w_.config_.randomize_appearance) RandomizeAppearance();
  offscreen_ = std::make_unique<OffscreenRenderer>(w_.model_, w_.config_.gl_backend);
  // the rendered camera's shared tables (noise samples, distortion maps) are computed beside the
  // rest of the start (this world, the flight stack, the GL context); its first frame waits
  if (w_.config_.camera.kind == CameraKind::kRendered) {
    camera_tables_ = std::async(std::launch::async,
                                [params = w_.world_params_, profile = w_.config_.profile.camera] {
                                  CameraImageModel::PrepareTablesFor(params, profile);
                                });
  }
}

Renderer::~Renderer() {
  offscreen_.reset();
  if (subframe_data_ != nullptr) mj_deleteData(subframe_data_);
}

bool Renderer::PrewarmForFork(const WorldConfig& config) {
  if (config.gl_backend != GlBackend::kOsMesa) return false;
  const char* threads = std::getenv("LP_NUM_THREADS");
  if (threads != nullptr && std::string(threads) != "0") return false;
  if (GlContext::created_any()) return false;  // llvmpipe started with its default threads
  setenv("LP_NUM_THREADS", "0", 1);  // read when llvmpipe starts: before the first context
  GlContext::SetReuse(true);
  World world(config);
  cv::Mat frame;
  world.renderer().RenderPayloadCamera(&frame);
  return true;  // the world's renderer recycles its context as the world goes
}

void Renderer::RandomizeAppearance() {
  // what the camera sees varies, the physics does not: floor shade and checker scale, and the
  // lights' strength and direction (no saturated colour: the detector looks for red)
  std::mt19937_64 rng(DeriveSeed(w_.config_.seed, SeedStream::kAppearance));
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int floor_mat = w_.model_->geom_matid[w_.ids_.ground_geom];
  if (floor_mat >= 0) {
    const double shade = 0.6 + 0.8 * u(rng);  // darker to brighter grey, a slight warm/cool cast
    const double cast = 0.08 * (u(rng) - 0.5);
    w_.model_->mat_rgba[4 * floor_mat + 0] = static_cast<float>(std::min(1.0, shade * (1 + cast)));
    w_.model_->mat_rgba[4 * floor_mat + 1] = static_cast<float>(std::min(1.0, shade));
    w_.model_->mat_rgba[4 * floor_mat + 2] = static_cast<float>(std::min(1.0, shade * (1 - cast)));
    const double repeat = 10.0 + 30.0 * u(rng);  // checker squares 0.25-1 m
    w_.model_->mat_texrepeat[2 * floor_mat + 0] = static_cast<float>(repeat);
    w_.model_->mat_texrepeat[2 * floor_mat + 1] = static_cast<float>(repeat);
  }
  const double head_diffuse = 0.35 + 0.5 * u(rng), head_ambient = 0.2 + 0.3 * u(rng);
  for (int k = 0; k < 3; ++k) {
    w_.model_->vis.headlight.diffuse[k] = static_cast<float>(head_diffuse);
    w_.model_->vis.headlight.ambient[k] = static_cast<float>(head_ambient);
  }
  for (int l = 0; l < w_.model_->nlight; ++l) {
    const double strength = 0.2 + 0.6 * u(rng);
    for (int k = 0; k < 3; ++k) w_.model_->light_diffuse[3 * l + k] = static_cast<float>(strength);
    const double azimuth = 2.0 * M_PI * u(rng), elevation = 0.6 + 0.9 * u(rng);  // rad
    w_.model_->light_dir[3 * l + 0] = std::cos(azimuth) * std::cos(elevation);
    w_.model_->light_dir[3 * l + 1] = std::sin(azimuth) * std::cos(elevation);
    w_.model_->light_dir[3 * l + 2] = -std::sin(elevation);
  }
}

cv::Mat Renderer::RenderPayloadCamera() {
  cv::Mat bgr;
  RenderPayloadCamera(&bgr, cv::Rect());
  return bgr;
}

Eigen::Vector2d Renderer::PayloadImageMotionPx(cv::Rect* region) const {
  const Params& p = w_.world_params_;
  const double f_px =
      camera_image_ != nullptr ? camera_image_->render_focal_px() : p.CameraFocalPx();
  const double exposure_s = w_.config_.profile.camera.exposure_s;
  // camera pose and velocity from the quadrotor's
  const double* q = w_.data_->xquat + 4 * w_.ids_.quad_body;
  const Eigen::Matrix3d R_WB =
      Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
  const Eigen::Map<const Eigen::Vector3d> p_WQ_W(w_.data_->xpos + 3 * w_.ids_.quad_body);
  const Eigen::Map<const Eigen::Vector3d> p_WL_W(w_.data_->xpos + 3 * w_.ids_.payload_body);
  const double* vq = w_.data_->qvel + w_.ids_.quad_jnt_dof;  // linear (world), angular (body)
  const double* vl = w_.data_->qvel + w_.ids_.payload_jnt_dof;
  const Eigen::Vector3d v_WQ_W(vq[0], vq[1], vq[2]), w_B(vq[3], vq[4], vq[5]);
  const Eigen::Vector3d v_WL_W(vl[0], vl[1], vl[2]);
  const Eigen::Matrix3d R_WC = R_WB * p.R_BC;
  const Eigen::Vector3d p_WC_W = p_WQ_W + R_WB * p.t_BC_B_m;
  const Eigen::Vector3d v_WC_W = v_WQ_W + R_WB * w_B.cross(p.t_BC_B_m);
  const Eigen::Vector3d w_C = p.R_BC.transpose() * w_B;
  const Eigen::Vector3d p_CL_C = R_WC.transpose() * (p_WL_W - p_WC_W);
  // d/dt of p_CL_C: relative velocity seen from the rotating camera
  const Eigen::Vector3d v_CL_C = R_WC.transpose() * (v_WL_W - v_WC_W) - w_C.cross(p_CL_C);
  const double z = p_CL_C.z();
  const double cx = 0.5 * p.camera_width_px, cy = 0.5 * p.camera_height_px;
  if (region != nullptr) *region = cv::Rect();
  if (!(z > p.payload_radius_m)) return Eigen::Vector2d::Zero();
  const Eigen::Vector2d rate_px(f_px * (v_CL_C.x() * z - p_CL_C.x() * v_CL_C.z()) / (z * z),
                                f_px * (v_CL_C.y() * z - p_CL_C.y() * v_CL_C.z()) / (z * z));
  if (region != nullptr) {
    const double r_px =
        f_px * p.payload_radius_m / std::sqrt(z * z - std::pow(p.payload_radius_m, 2));
    const double u = cx + f_px * p_CL_C.x() / z, v = cy + f_px * p_CL_C.y() / z;
    // a sphere off-axis images as an ellipse up to 1 / cos^2 of the ray angle wider: 2 r covers
    const int half = static_cast<int>(std::ceil(2.0 * r_px)) + 2;
    *region = cv::Rect(static_cast<int>(u) - half, static_cast<int>(v) - half, 2 * half, 2 * half) &
              cv::Rect(0, 0, p.camera_width_px, p.camera_height_px);
  }
  return rate_px * exposure_s;
}

void Renderer::RenderPayloadCamera(cv::Mat* bgr, const cv::Rect& region) {
  using Clock = std::chrono::steady_clock;
  const auto ms = [](Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
  };
  const CameraImageProfile& profile = w_.config_.profile.camera;
  if (camera_image_ == nullptr) {
    // the GL state first, while the tables may still be computed; then the model on them
    offscreen_->Prepare();
    if (camera_tables_.valid()) camera_tables_.get();
    camera_image_ = std::make_unique<CameraImageModel>(
        w_.world_params_, profile, DeriveSeed(w_.config_.seed, SeedStream::kCameraImage));
    // the render is a pinhole image wide enough to cover the distorted sensor
    w_.model_->cam_fovy[w_.ids_.payload_camera] = camera_image_->render_fovy_deg();
  }
  const int w = w_.model_->vis.global.offwidth, h = w_.model_->vis.global.offheight;
  // a camera fault's distractors drawn at this instant: copies of the payload's sphere
  if (!w_.faults_.empty()) {
    offscreen_->SetGeomCopies(w_.ids_.payload_geom, w_.faults_.DistractorPositions_W(w_.time_s()));
  }
  // noise keyed by the physics step: a region and the whole frame of one instant agree
  const uint64_t frame = static_cast<uint64_t>(w_.step_);
  const auto t0 = Clock::now();
  double render_ms = 0.0;
  if (profile.exposure_s > 0.0 && profile.motion_blur_subframes >= 2) {
    // reference motion blur: the average of renders at sub-frame times across the exposure,
    // every body moved with its current velocity (the exposure is centred on now); always the
    // whole frame, which a region request reads its part of
    if (subframe_data_ == nullptr) subframe_data_ = mj_makeData(w_.model_);
    const int n = profile.motion_blur_subframes;
    subframe_sum_.create(h, w, CV_32FC3);
    subframe_sum_.setTo(cv::Scalar::all(0.0));
    for (int i = 0; i < n; ++i) {
      const double dt_s = ((i + 0.5) / n - 0.5) * profile.exposure_s;
      mj_copyData(subframe_data_, w_.model_, w_.data_);
      mj_integratePos(w_.model_, subframe_data_->qpos, subframe_data_->qvel, dt_s);
      mj_kinematics(w_.model_, subframe_data_);
      mj_comPos(w_.model_, subframe_data_);
      mj_camlight(w_.model_, subframe_data_);
      mj_tendon(w_.model_, subframe_data_);
      offscreen_->Render(subframe_data_, w_.ids_.payload_camera, w, h, profile.draw_cable,
                         &subframe_);
      cv::accumulate(subframe_, subframe_sum_);
    }
    subframe_sum_.convertTo(pinhole_, CV_8UC3, 1.0 / n);
    const auto t1 = Clock::now();
    render_ms = ms(t0, t1);
    camera_image_->ApplyOptics(pinhole_, frame, bgr);
  } else {
    cv::Rect blur_region;
    const Eigen::Vector2d blur_px =
        profile.exposure_s > 0.0 ? PayloadImageMotionPx(&blur_region) : Eigen::Vector2d::Zero();
    const cv::Rect render_region =
        region.area() > 0 ? camera_image_->RenderRegion(region, blur_px) : cv::Rect();
    offscreen_->Render(w_.data_, w_.ids_.payload_camera, w, h, profile.draw_cable, &pinhole_,
                       render_region);
    const auto t1 = Clock::now();
    render_ms = ms(t0, t1);
    camera_image_->Apply(pinhole_, blur_px, blur_region, frame, bgr, region);
  }
  camera_timing_.render_ms = render_ms;
  camera_timing_.image_model_ms = ms(t0, Clock::now()) - render_ms;
}

cv::Mat Renderer::RenderChaseCamera(int width_px, int height_px) {
  // the gripper (group 3) while it holds the payload
  offscreen_->SetGeomGroupVisible(kGripperGeomGroup,
                                  w_.model_->eq_active[w_.ids_.gripper_weld] != 0);
  if (!w_.faults_.empty()) {
    offscreen_->SetGeomCopies(w_.ids_.payload_geom, w_.faults_.DistractorPositions_W(w_.time_s()));
  }
  const cv::Mat frame = offscreen_->Render(w_.data_, w_.ids_.chase_camera, width_px, height_px);
  offscreen_->SetGeomGroupVisible(kGripperGeomGroup, false);
  return frame;
}

}  // namespace hpa::sim
