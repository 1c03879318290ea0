// hpa::sim::TeamRenderer: the team video's cameras (OSMesa). The chase camera sees the payload and
// every vehicle, an onboard camera sees the payload hanging below it, a slack cable is drawn
// orange, and rendering never changes the world it draws.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <stdexcept>
#include <vector>

#include "hpa/models/cooperative_model.h"
#include "hpa/models/params.h"
#include "hpa/sim/team_renderer.h"
#include "hpa/sim/team_world.h"

namespace hpa::sim {
namespace {

using Eigen::Vector3d;

// Three params.yaml vehicles on a 0.3 kg plate, attachments on a 0.2 m circle, cables 0.5, 0.6
// and 0.7 m (team_world_test's triangle).
CooperativeTeam Triangle() {
  const Params p = LoadParams(DefaultParamsPath());
  CooperativeTeam team;
  team.payload_mass_kg = 0.3;
  team.payload_inertia_P_kgm2 = Vector3d(3e-3, 3e-3, 6e-3);
  team.gravity_mps2 = p.gravity_mps2;
  for (int i = 0; i < 3; ++i) {
    CooperativeVehicle v;
    v.params = p;
    v.cable_length_m = 0.5 + 0.1 * i;
    const double a = 2 * M_PI * i / 3;
    v.p_PA_P_m = 0.2 * Vector3d(std::cos(a), std::sin(a), 0);
    team.vehicles.push_back(v);
  }
  return team;
}

TeamWorldConfig Config(const CooperativeTeam& team) {
  TeamWorldConfig c;
  c.team = team;
  return c;
}

// Pixels of `bgr` for which `is` holds, and their mean column and row.
struct Blob {
  int pixels = 0;
  double u_px = 0.0, v_px = 0.0;
};
Blob Find(const cv::Mat& bgr, const std::function<bool(int b, int g, int r)>& is) {
  Blob blob;
  for (int v = 0; v < bgr.rows; ++v) {
    for (int u = 0; u < bgr.cols; ++u) {
      const cv::Vec3b& p = bgr.at<cv::Vec3b>(v, u);
      if (!is(p[0], p[1], p[2])) continue;
      ++blob.pixels;
      blob.u_px += u;
      blob.v_px += v;
    }
  }
  if (blob.pixels > 0) {
    blob.u_px /= blob.pixels;
    blob.v_px /= blob.pixels;
  }
  return blob;
}

// the payload's red (the floor and bodies are grey, the rotor discs blue, green or yellow)
bool Red(int b, int g, int r) { return r > 100 && r > 2 * g && r > 2 * b; }

TEST(TeamRenderTest, ChaseCameraSeesThePayloadAndEveryVehicle) {
  TeamWorld world(Config(Triangle()));
  const cv::Mat chase = world.renderer().RenderChaseCamera(960, 540);
  ASSERT_EQ(chase.type(), CV_8UC3);
  ASSERT_EQ(chase.cols, 960);
  ASSERT_EQ(chase.rows, 540);
  const Blob payload = Find(chase, Red);
  EXPECT_GT(payload.pixels, 20);
  // each vehicle's rotor discs in its own colour: blue, green, yellow (dominant channels)
  const std::vector<std::function<bool(int, int, int)>> vehicle_colour = {
      [](int b, int g, int r) { return b > 120 && b > r + 60 && b > g + 20; },
      [](int b, int g, int r) { return g > 100 && g > r + 40 && g > b + 40; },
      [](int b, int g, int r) { return r > 120 && g > 100 && b < g / 2; }};
  for (int i = 0; i < 3; ++i) {
    const Blob discs = Find(chase, vehicle_colour[i]);
    EXPECT_GT(discs.pixels, 10) << "vehicle " << i;
    // above the payload in the picture: the vehicles hang their cables' length higher
    EXPECT_LT(discs.v_px, payload.v_px) << "vehicle " << i;
  }
}

TEST(TeamRenderTest, OnboardCameraSeesThePayloadBelowIt) {
  // one vehicle: the payload hangs straight under its camera, near the image centre (the
  // camera sits 3 cm forward of the cable: about 8 px off at 0.45 m with a 75 deg, 180 px fovy)
  TeamWorld world(Config(CooperativeTeam::SingleVehicle(LoadParams(DefaultParamsPath()))));
  const cv::Mat onboard = world.renderer().RenderOnboardCamera(0);
  ASSERT_EQ(onboard.cols, TeamRenderer::kOnboardWidthPx);
  ASSERT_EQ(onboard.rows, TeamRenderer::kOnboardHeightPx);
  const Blob payload = Find(onboard, Red);
  EXPECT_GT(payload.pixels, 50);
  EXPECT_NEAR(payload.u_px, 0.5 * onboard.cols, 20.0);
  EXPECT_NEAR(payload.v_px, 0.5 * onboard.rows, 20.0);
  EXPECT_THROW(world.renderer().RenderOnboardCamera(1), std::out_of_range);
  EXPECT_THROW(world.renderer().RenderOnboardCamera(-1), std::out_of_range);
}

TEST(TeamRenderTest, ASlackCableIsDrawnOrange) {
  // two vehicles (blue and green discs: no colour near the cable's orange) on a bar; vehicle 1
  // pushed down slackens its cable
  CooperativeTeam team = Triangle();
  team.vehicles.pop_back();
  TeamWorld world(Config(team));
  const auto orange = [](int b, int g, int r) { return r > 200 && g > 90 && g < 180 && b < 60; };
  EXPECT_EQ(Find(world.renderer().RenderChaseCamera(960, 540), orange).pixels, 0);
  world.ApplyImpulse(1, Vector3d(0, 0, -1.0), 0.001);
  for (int k = 0; k < 30 && world.GetTruth().modes[1] == CableMode::kTaut; ++k) world.Step();
  ASSERT_EQ(world.GetTruth().modes[1], CableMode::kSlack);
  EXPECT_GT(Find(world.renderer().RenderChaseCamera(960, 540), orange).pixels, 20);
}

TEST(TeamRenderTest, RenderingNeverChangesTheWorld) {
  // two worlds flown alike, one rendered every 10 steps: the same truth and sensors, bit for bit
  const TeamWorldConfig config = Config(Triangle());
  TeamWorld plain(config), rendered(config);
  for (int k = 0; k < 200; ++k) {
    if (k == 50) {
      plain.ApplyImpulse(1, Vector3d(0, 0, -0.5), 0.001);  // a slack cable on the way
      rendered.ApplyImpulse(1, Vector3d(0, 0, -0.5), 0.001);
    }
    if (k % 10 == 0) {
      cv::Mat frame;
      rendered.renderer().RenderChaseCamera(320, 180, &frame);
      for (int i = 0; i < 3; ++i) rendered.renderer().RenderOnboardCamera(i, 160, 90, &frame);
    }
    plain.Step();
    rendered.Step();
    const TeamTruth a = plain.GetTruth(), b = rendered.GetTruth();
    ASSERT_EQ(a.x, b.x) << "step " << k;
    ASSERT_EQ(a.cable_tension_N, b.cable_tension_N) << "step " << k;
    for (int i = 0; i < 3; ++i) ASSERT_EQ(plain.GyroSample_B(i), rendered.GyroSample_B(i));
    const std::vector<BodyReading> ra = plain.TakeDelivered(), rb = rendered.TakeDelivered();
    ASSERT_EQ(ra.size(), rb.size());
    for (size_t r = 0; r < ra.size(); ++r) ASSERT_EQ(ra[r].p_W_m, rb[r].p_W_m);
  }
}

}  // namespace
}  // namespace hpa::sim
