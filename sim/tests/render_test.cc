// The payload camera renders the payload where the camera model puts it: a red blob at the
// image centre of radius f * R / d, when hovering with the payload hanging below.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "hpa/models/camera_model.h"
#include "hpa/models/params.h"
#include "hpa/sim/camera_image_model.h"
#include "hpa/sim/faults.h"
#include "hpa/sim/world.h"
#include "sim/src/world_internals.h"
#include "swung_payload.h"

namespace hpa::sim {
namespace {

// Pixels that are clearly pure-ish red (the payload material), as a binary mask.
cv::Mat RedMask(const cv::Mat& bgr) {
  cv::Mat hsv, low, high;
  cv::cvtColor(bgr, hsv, cv::COLOR_BGR2HSV);
  cv::inRange(hsv, cv::Scalar(0, 150, 80), cv::Scalar(8, 255, 255), low);
  cv::inRange(hsv, cv::Scalar(172, 150, 80), cv::Scalar(180, 255, 255), high);
  return low | high;
}

TEST(RenderTest, PayloadIsARedBlobWhereTheCameraModelPutsIt) {
  WorldConfig config;
  config.params = LoadParams(DefaultParamsPath());
  config.profile.camera.draw_cable = false;  // geometry of the ball alone
  World world(config);  // default Reset: hovering at 1 m, payload hanging l below
  const Params& p = world.world_params();
  world.SetMotorSpeedCommand(InputVector::Constant(p.HoverMotorSpeedRadps()));
  world.Step();

  const cv::Mat frame = world.renderer().RenderPayloadCamera();
  ASSERT_EQ(frame.type(), CV_8UC3);
  ASSERT_EQ(frame.cols, p.camera_width_px);
  ASSERT_EQ(frame.rows, p.camera_height_px);
  const std::string png = testing::TempDir() + "/payload_camera_hover.png";
  ASSERT_TRUE(cv::imwrite(png, frame));
  std::printf("[written] %s\n", png.c_str());

  // the largest red blob
  const cv::Mat mask = RedMask(frame);
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask.clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  ASSERT_FALSE(contours.empty()) << "no red pixels";
  size_t best = 0;
  for (size_t i = 1; i < contours.size(); ++i) {
    if (cv::contourArea(contours[i]) > cv::contourArea(contours[best])) best = i;
  }
  // contour moments use pixel-index coordinates (pixel i centred at i); the camera model's pixel
  // i spans [i, i + 1) (centre at W / 2), hence + 0.5
  const cv::Moments mo = cv::moments(contours[best]);
  const double u = mo.m10 / mo.m00 + 0.5, v = mo.m01 / mo.m00 + 0.5;
  const double radius_px = std::sqrt(mo.m00 / M_PI);

  // expected: straight below the cable's attachment, the camera t_BC beside it; distance d to
  // the sphere's centre; a sphere's image is (nearly) a disc of radius f R / sqrt(d^2 - R^2),
  // centred where the camera model and the lens put it
  SystemState hanging;
  hanging.p_WQ_W = Eigen::Vector3d(0, 0, 1);
  hanging.p_WL_W = Eigen::Vector3d(0, 0, 1 - p.cable_length_m);
  const Eigen::Vector3d p_CL_C = PayloadInCamera_C(p, hanging);
  const Eigen::Vector2d expected_px = DistortPixel(p, *ProjectToPixels(p, p_CL_C));
  const double d_m = p_CL_C.norm();
  const double f_px = p.CameraFocalPx();
  const double r_m = p.payload_radius_m;
  const double expected_radius_px = f_px * r_m / std::sqrt(d_m * d_m - r_m * r_m);
  std::printf(
      "[measured] blob centre (%.1f, %.1f) px (expected (%.1f, %.1f)), radius %.2f px "
      "(f R / d = %.2f px)\n",
      u, v, expected_px.x(), expected_px.y(), radius_px, expected_radius_px);
  // centre: 0.5 px (a one-pixel shift or flip fails)
  EXPECT_NEAR(u, expected_px.x(), 0.5);
  EXPECT_NEAR(v, expected_px.y(), 0.5);
  // radius: 5 % (the shaded rim darkens below the threshold); measured 41.2 vs 41.9 px (1.6 %)
  EXPECT_NEAR(radius_px, expected_radius_px, 0.05 * expected_radius_px);
  // nothing else in the frame is red
  EXPECT_NEAR(cv::countNonZero(mask), mo.m00, 0.05 * mo.m00);
}

TEST(RenderTest, PayloadMovesInTheImageAsTheCameraModelSays) {
  // payload swung +x and +y, quadrotor rolled, pitched and yawed: the rendered blob must sit where
  // hpa::PayloadInCamera_C + ProjectToPixels (models/camera_model.h) put it
  WorldConfig config;
  config.params = LoadParams(DefaultParamsPath());
  config.profile.camera.draw_cable = false;  // geometry of the ball alone
  World world(config);
  const Params& p = world.world_params();
  const SystemState s = testing_poses::SwungPayload(/*tilted=*/true);
  world.SetState(s.ToVector(), InputVector::Constant(p.HoverMotorSpeedRadps()));
  const cv::Mat frame = world.renderer().RenderPayloadCamera();
  cv::imwrite(testing::TempDir() + "/payload_camera_offset.png", frame);
  const cv::Moments mo = cv::moments(RedMask(frame), true);
  ASSERT_GT(mo.m00, 100);
  const double u = mo.m10 / mo.m00 + 0.5, v = mo.m01 / mo.m00 + 0.5;  // see the first test
  const auto ideal_px = ProjectToPixels(p, PayloadInCamera_C(p, s));
  ASSERT_TRUE(ideal_px.has_value());
  const std::optional<Eigen::Vector2d> px = DistortPixel(p, *ideal_px);  // through the lens
  std::printf("[measured] offset blob (%.2f, %.2f) px, camera model (%.2f, %.2f) px\n", u, v,
              px->x(), px->y());
  // 3 px: off the axis a sphere images as an ellipse whose centroid lies slightly outward of the
  // projected centre (perspective): measured 1.6 px, mostly along the offset
  EXPECT_NEAR(u, px->x(), 3.0);
  EXPECT_NEAR(v, px->y(), 3.0);
}

// A region of the payload camera's image, rendered and processed alone, equals the whole
// frame's pixels there (the frustum narrowed to the region; noise keyed by the pixel's place).
TEST(RenderTest, RegionEqualsTheWholeFrameThere) {
  WorldConfig config;
  config.params = LoadParams(DefaultParamsPath());
  config.profile.camera.noise = true;
  config.profile.camera.analog_gain = 4.0;
  config.profile.camera.exposure_s = 0.005;
  World world(config);
  const Params& p = world.world_params();
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0, 0, 1);
  s.p_WL_W = s.p_WQ_W + Eigen::Vector3d(0.12, -0.08, -std::sqrt(0.25 - 0.12 * 0.12 - 0.08 * 0.08));
  s.v_WL_W = Eigen::Vector3d(0.5, 0.3, 0.0);  // motion blur on
  world.SetState(s.ToVector(), InputVector::Constant(p.HoverMotorSpeedRadps()));
  cv::Mat whole, part;
  world.renderer().RenderPayloadCamera(&whole);
  double max_diff = 0.0, sum_diff = 0.0;
  long values = 0;
  for (const cv::Rect region :
       {cv::Rect(700, 200, 180, 160), cv::Rect(0, 0, 150, 120), cv::Rect(1200, 640, 80, 80)}) {
    part = cv::Mat::zeros(whole.size(), whole.type());
    world.renderer().RenderPayloadCamera(&part, region);
    cv::Mat diff;
    cv::absdiff(whole(region), part(region), diff);
    double mx = 0.0;
    cv::minMaxLoc(diff.reshape(1), nullptr, &mx);
    max_diff = std::max(max_diff, mx);
    sum_diff += cv::sum(diff)[0] + cv::sum(diff)[1] + cv::sum(diff)[2];
    values += static_cast<long>(region.area()) * 3;
    // nothing outside the region is written
    EXPECT_EQ(cv::countNonZero(part.reshape(1)), cv::countNonZero(part(region).clone().reshape(1)));
  }
  const double mean_diff = sum_diff / values;
  std::printf("[measured] region vs whole frame: max %.0f levels, mean %.4f levels\n", max_diff,
              mean_diff);
  // rasterisation of the narrowed frustum may round an edge pixel differently (float frustum):
  // measured 1 level at most, mean 0.0003 levels; bounds 2 levels and 10x the mean
  EXPECT_LE(max_diff, 2.0);
  EXPECT_LT(mean_diff, 0.003);
}

// The fast motion-blur approximation (the payload's image motion as a line kernel over its
// region) against the reference (the average of exact renders across the exposure), on a payload
// swinging fast across the view: the payload's blob and its centroid agree.
// The camera's exposure: the region the flight stack asked for is read at capture, the whole
// frame of the same exposure only when asked (equal to the region there); a stuck camera repeats
// its first whole frame, a garbage one gives one noise image per capture.
TEST(RenderTest, AnExposureReadsItsRegionFirstAndTheWholeFrameOnlyWhenAsked) {
  WorldConfig config;
  config.params = LoadParams(DefaultParamsPath());
  config.camera.kind = CameraKind::kRendered;
  World world(config);
  world.SetMotorSpeedCommand(InputVector::Constant(world.world_params().HoverMotorSpeedRadps()));
  const cv::Rect region(config.params.camera_width_px / 2 - 100,
                        config.params.camera_height_px / 2 - 100, 200, 200);
  ASSERT_TRUE(world.CameraFrameDue());
  std::optional<CameraCapture> capture = world.CaptureTickStart(region);
  ASSERT_TRUE(capture.has_value() && capture->exposure.has_value());
  CameraExposure& exposure = *capture->exposure;
  EXPECT_EQ(exposure.frame().region, region);
  EXPECT_FALSE(exposure.whole_read());
  const cv::Mat region_pixels = exposure.frame().region_bgr(region).clone();
  ASSERT_GT(cv::countNonZero(RedMask(region_pixels)), 100) << "the payload is in the region";
  const cv::Mat& whole = exposure.ReadWhole();
  EXPECT_TRUE(exposure.whole_read());
  ASSERT_EQ(whole.cols, config.params.camera_width_px);
  // equal up to the image model's rounding (RegionEqualsTheWholeFrameThere's bound)
  EXPECT_LE(cv::norm(whole(region), region_pixels, cv::NORM_INF), 2.0);

  // stuck from the next frame: its first whole frame again, though the vehicle has moved
  const auto next_capture = [&](const cv::Rect& r) {
    std::optional<CameraCapture> c;
    while (!(c = world.CaptureTickStart(r))) world.Step();
    world.Step();
    return c;
  };
  world.SetMotorSpeedCommand(InputVector::Constant(world.world_params().HoverMotorSpeedRadps()) *
                             1.1);
  world.Step();
  Fault stuck;
  stuck.component = FaultComponent::kCamera;
  stuck.mode = FaultMode::kStuck;
  stuck.start_s = world.time_s();
  stuck.end_s = world.time_s() + 0.2;
  world.faults().Inject(stuck);
  std::optional<CameraCapture> first = next_capture(region);
  const cv::Mat first_whole = first->exposure->ReadWhole().clone();
  std::optional<CameraCapture> later = next_capture(region);
  EXPECT_EQ(
      cv::norm(later->exposure->frame().region_bgr(region), first_whole(region), cv::NORM_INF),
      0.0);
  EXPECT_EQ(cv::norm(later->exposure->ReadWhole(), first_whole, cv::NORM_INF), 0.0);
  while (world.time_s() < stuck.end_s) world.Step();
  std::optional<CameraCapture> after = next_capture(region);
  EXPECT_GT(cv::norm(after->exposure->ReadWhole(), first_whole, cv::NORM_INF), 0.0)
      << "the camera moves on once the fault ends";

  // garbage: uniform noise (mean level 127.5 in every channel), the region the whole frame's
  Fault garbage = stuck;
  garbage.mode = FaultMode::kGarbage;
  garbage.start_s = world.time_s();
  garbage.end_s = world.time_s() + 0.2;
  world.faults().Inject(garbage);
  std::optional<CameraCapture> noisy = next_capture(region);
  const cv::Mat noisy_region = noisy->exposure->frame().region_bgr(region).clone();
  EXPECT_EQ(cv::norm(noisy->exposure->ReadWhole()(region), noisy_region, cv::NORM_INF), 0.0);
  const cv::Scalar mean_level = cv::mean(noisy_region);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean_level[c], 127.5, 3.0) << "channel " << c;
}

TEST(RenderTest, FastMotionBlurMatchesSubFrameReference) {
  const auto render = [](int subframes, double exposure_s) {
    WorldConfig config;
    config.params = LoadParams(DefaultParamsPath());
    config.profile.camera.exposure_s = exposure_s;
    config.profile.camera.motion_blur_subframes = subframes;
    config.profile.camera.draw_cable = false;  // the ball alone
    World world(config);
    const Params& p = world.world_params();
    SystemState s = testing_poses::SwungPayload(/*tilted=*/false);
    s.v_WL_W = Eigen::Vector3d(2.0, -1.0, 0.4);  // 2.3 m/s: a whirl after an impulse
    world.SetState(s.ToVector(), InputVector::Constant(p.HoverMotorSpeedRadps()));
    return world.renderer().RenderPayloadCamera();
  };
  const cv::Mat sharp = render(0, 0.0);
  const cv::Mat fast = render(0, 0.005);
  const cv::Mat reference = render(16, 0.005);
  const auto centroid = [](const cv::Mat& bgr) {
    const cv::Moments mo = cv::moments(RedMask(bgr), true);
    return Eigen::Vector3d(mo.m10 / mo.m00, mo.m01 / mo.m00, mo.m00);
  };
  const Eigen::Vector3d c_sharp = centroid(sharp), c_fast = centroid(fast),
                        c_ref = centroid(reference);
  // the blob's extent along the motion grows with the blur in both
  cv::Mat diff_fast, diff_sharp;
  cv::absdiff(fast, reference, diff_fast);
  cv::absdiff(sharp, reference, diff_sharp);
  const cv::Rect ball = cv::boundingRect(RedMask(reference)) + cv::Size(20, 20) - cv::Point(10, 10);
  const double mean_fast = cv::mean(diff_fast(ball))[2], mean_sharp = cv::mean(diff_sharp(ball))[2];
  std::printf(
      "[measured] red-blob centroid: sharp (%.2f, %.2f), fast (%.2f, %.2f), reference (%.2f, "
      "%.2f); area %.0f / %.0f / %.0f px; mean |red - reference| around the ball: fast %.2f, "
      "unblurred %.2f levels\n",
      c_sharp.x(), c_sharp.y(), c_fast.x(), c_fast.y(), c_ref.x(), c_ref.y(), c_sharp.z(),
      c_fast.z(), c_ref.z(), mean_fast, mean_sharp);
  // measured: centroids within 0.04 px; around the ball the fast image is 0.37 levels from the
  // reference on average where the unblurred one is 3.47 (ratio 0.11). Bounds twice that: the
  // approximation must remove most of the blur's effect, and keep the centroid (the blur is
  // centred on the capture time)
  EXPECT_NEAR(c_fast.x(), c_ref.x(), 0.1);
  EXPECT_NEAR(c_fast.y(), c_ref.y(), 0.1);
  EXPECT_LT(mean_fast, 0.75);
  EXPECT_LT(mean_fast, 0.22 * mean_sharp);
}

// estimation.camera_randomize: floor and lights drawn from the seed, the same seed the same frame.
// The fast motion blur fades into the unblurred background: on a textured frame smeared around a
// box, the per-column difference from the unblurred image falls off without a step where the
// smeared area ends (a hard seam there is a step as large as the smear's whole effect).
TEST(RenderTest, FastMotionBlurLeavesNoSeam) {
  Params params = LoadParams(DefaultParamsPath());
  params.camera_distortion.setZero();  // sensor columns are render columns
  CameraImageProfile profile;
  profile.psf_sigma_px = 0.0;
  profile.exposure_s = 0.005;
  CameraImageModel model(params, profile, 1);
  // a checkerboard of 6 px squares: every smear along x changes it
  cv::Mat pinhole(params.camera_height_px, params.camera_width_px, CV_8UC3);
  for (int row = 0; row < pinhole.rows; ++row) {
    for (int col = 0; col < pinhole.cols; ++col) {
      const uint8_t level = ((row / 6 + col / 6) % 2) != 0 ? 200 : 40;
      pinhole.at<cv::Vec3b>(row, col) = cv::Vec3b(level, level, level);
    }
  }
  const cv::Rect box(600, 300, 60, 60);
  cv::Mat sharp, smeared;
  model.Apply(pinhole, Eigen::Vector2d::Zero(), cv::Rect(), 0, &sharp);
  model.Apply(pinhole, Eigen::Vector2d(20.0, 0.0), box, 0, &smeared);
  cv::Mat diff;
  cv::absdiff(smeared, sharp, diff);
  // mean difference per column over the box's rows, from the box's centre out to the right
  std::vector<double> per_column;
  for (int col = box.x + box.width / 2; col < box.x + box.width + 120; ++col) {
    per_column.push_back(cv::mean(diff(cv::Rect(col, box.y, 1, box.height)))[0]);
  }
  double largest_step = 0.0;
  for (size_t i = 1; i < per_column.size(); ++i) {
    largest_step = std::max(largest_step, std::abs(per_column[i] - per_column[i - 1]));
  }
  const double inside = per_column.front();
  std::printf("[measured] smear effect inside %.1f levels, largest column-to-column step %.2f\n",
              inside, largest_step);
  // the smear must act inside (a checkerboard smeared 20 px loses most of its contrast), fade
  // to nothing outside, and never step by more than a fifth of its effect between two columns.
  // Measured: effect 84 levels, largest step 10 (the checkerboard's own ripple under the smear);
  // the hard-edged smear stepped by its whole effect where it ended
  EXPECT_GT(inside, 40.0);
  EXPECT_LT(per_column.back(), 0.5);
  EXPECT_LT(largest_step, 0.2 * inside);
}

TEST(RenderTest, RandomizedAppearanceVariesBySeedOnly) {
  const auto frame = [](uint64_t seed, bool randomize) {
    WorldConfig config;
    config.params = LoadParams(DefaultParamsPath());
    config.seed = seed;
    config.randomize_appearance = randomize;
    World world(config);
    return world.renderer().RenderPayloadCamera();
  };
  const auto mean_diff = [](const cv::Mat& a, const cv::Mat& b) {
    cv::Mat d;
    cv::absdiff(a, b, d);
    const cv::Scalar m = cv::mean(d);
    return (m[0] + m[1] + m[2]) / 3.0;
  };
  const double same_seed = mean_diff(frame(1, true), frame(1, true));
  const double other_seed = mean_diff(frame(1, true), frame(2, true));
  const double fixed = mean_diff(frame(1, false), frame(2, false));
  std::printf(
      "[measured] mean |difference|: same seed %.2f, seeds 1 vs 2 %.2f, fixed %.2f levels\n",
      same_seed, other_seed, fixed);
  EXPECT_EQ(same_seed, 0.0);
  EXPECT_EQ(fixed, 0.0);  // without randomize the seed changes nothing in a noise-free frame
  // measured 18.2 levels between seeds 1 and 2; a draw that barely changed the scene (a quarter
  // of that, about one checker shade step) fails
  EXPECT_GT(other_seed, 5.0);
}

TEST(RenderTest, ChaseCameraRendersRequestedSize) {
  WorldConfig config;
  config.params = LoadParams(DefaultParamsPath());
  World world(config);
  const cv::Mat frame = world.renderer().RenderChaseCamera(640, 360);
  EXPECT_EQ(frame.cols, 640);
  EXPECT_EQ(frame.rows, 360);
  cv::imwrite(testing::TempDir() + "/chase_camera.png", frame);
  EXPECT_GT(cv::countNonZero(RedMask(frame)), 10) << "payload visible from the chase camera";
  EXPECT_THROW(world.renderer().RenderChaseCamera(4000, 10), std::invalid_argument);
}

// Leaving out the geoms a frame cannot show (the quadrotor's body and rotors behind the camera,
// the sites, the slack cable's catenary behind the payload, what lies outside a region) changes
// no pixel: the payload camera's whole frame and regions and the chase camera, culling on and off.
TEST(RenderTest, CullingHiddenGeomsChangesNoPixel) {
  WorldConfig config;
  config.params = LoadParams(DefaultParamsPath());
  config.profile.camera.noise = true;
  World world(config);
  OffscreenRenderer& renderer = WorldInternals::Renderer(world);
  const double hover = world.world_params().HoverMotorSpeedRadps();
  SystemState slack;  // payload lifted 0.25 m and aside: the cable hangs as a catenary
  slack.p_WQ_W = Eigen::Vector3d(0, 0, 1);
  slack.p_WL_W = Eigen::Vector3d(0.1, 0.05, 0.75);
  SystemState slack_below = slack;  // straight below: the catenary hangs behind the payload
  slack_below.p_WL_W = Eigen::Vector3d(0.0, 0.005, 0.75);
  int culled_max = 0;
  for (const SystemState& s : {slack, slack_below, testing_poses::SwungPayload(false),
                               testing_poses::SwungPayload(true)}) {
    world.SetState(s.ToVector(), InputVector::Constant(hover));
    const auto ideal =
        ProjectToPixels(world.world_params(), PayloadInCamera_C(world.world_params(), s));
    ASSERT_TRUE(ideal.has_value());
    const cv::Point c(static_cast<int>(ideal->x()), static_cast<int>(ideal->y()));
    for (const cv::Rect region :
         {cv::Rect(), cv::Rect(c.x - 150, c.y - 150, 300, 300),
          cv::Rect(c.x - 60, c.y - 60, 120, 120), cv::Rect(0, 0, 200, 150)}) {
      cv::Mat culled = cv::Mat::zeros(720, 1280, CV_8UC3), all = culled.clone();
      renderer.SetCullHiddenGeoms(true);
      world.renderer().RenderPayloadCamera(&culled, region);
      culled_max = std::max(culled_max, renderer.last_culled_geoms());
      renderer.SetCullHiddenGeoms(false);
      world.renderer().RenderPayloadCamera(&all, region);
      EXPECT_EQ(renderer.last_culled_geoms(), 0);
      EXPECT_EQ(cv::norm(culled, all, cv::NORM_INF), 0.0) << region;
    }
    renderer.SetCullHiddenGeoms(true);
    const cv::Mat chase_culled = world.renderer().RenderChaseCamera(320, 180);
    renderer.SetCullHiddenGeoms(false);
    EXPECT_EQ(cv::norm(chase_culled, world.renderer().RenderChaseCamera(320, 180), cv::NORM_INF),
              0.0);
  }
  std::printf("[measured] at most %d geoms culled from a frame\n", culled_max);
  // measured 42 (the body, rotor discs, sites and most of the catenary); 20 fails if the
  // catenary behind the payload were kept
  EXPECT_GE(culled_max, 20);
}

// A world whose renderer takes the GL state another world kept (what every run of a sweep does
// after Renderer::PrewarmForFork: the context with its compiled shaders and MuJoCo's GL resources)
// renders the same pixels as one with a state of its own, the payload camera and the chase camera
// alike; a world of a model that renders differently makes its own resources on the kept context.
TEST(RenderTest, ReusedContextRendersTheSamePixels) {
  WorldConfig config;
  config.params = LoadParams(DefaultParamsPath());
  config.profile.camera.noise = true;
  if (!Renderer::PrewarmForFork(config)) {
    GTEST_SKIP() << "this process rendered before (or LP_NUM_THREADS is set): run the test alone, "
                    "as ctest does";
  }
  SystemState s;
  s.p_WQ_W = Eigen::Vector3d(0, 0, 1);
  s.p_WL_W = s.p_WQ_W + Eigen::Vector3d(0.1, 0.05, -std::sqrt(0.25 - 0.01 - 0.0025));
  const auto frames = [&](World* world) {
    world->SetState(s.ToVector(),
                    InputVector::Constant(world->world_params().HoverMotorSpeedRadps()));
    cv::Mat payload;
    world->renderer().RenderPayloadCamera(&payload);
    return std::make_pair(payload, world->renderer().RenderChaseCamera(320, 180));
  };
  World reused(config);  // its renderer takes the kept state
  World fresh(config);   // that one is taken: this renderer makes its own
  const auto a = frames(&reused);
  const auto b = frames(&fresh);
  EXPECT_TRUE(WorldInternals::Renderer(reused).took_kept_state());
  EXPECT_FALSE(WorldInternals::Renderer(fresh).took_kept_state());
  EXPECT_EQ(cv::norm(a.first, b.first, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(a.second, b.second, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::countNonZero(RedMask(a.first)), 100) << "payload in the reused context's view";

  // a model whose resources differ (a plane of another size: another grid) does not take it
  std::unique_ptr<World> kept_by = std::make_unique<World>(config);
  frames(kept_by.get());
  kept_by.reset();  // keeps its state
  World other(config);
  mjModel* model = const_cast<mjModel*>(WorldInternals::Model(other));
  for (int g = 0; g < model->ngeom; ++g) {
    if (model->geom_type[g] == mjGEOM_PLANE) model->geom_size[3 * g] *= 0.5;
  }
  frames(&other);
  EXPECT_FALSE(WorldInternals::Renderer(other).took_kept_state());
}

}  // namespace
}  // namespace hpa::sim
