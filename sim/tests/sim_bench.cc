// Cost of the simulated world: one 1 ms physics step (motors, sensors, crash check, mj_step), one
// 1280x720 payload camera frame (OSMesa llvmpipe, shadows/reflection/skybox off) and the camera
// image model on a region the size the runner renders around the payload.
#include <benchmark/benchmark.h>

#include <opencv2/core.hpp>

#include "hpa/models/params.h"
#include "hpa/sim/camera_image_model.h"
#include "hpa/sim/world.h"
#include "sim/src/world_internals.h"

namespace {

hpa::sim::WorldConfig Config() {
  hpa::sim::WorldConfig c;
  c.params = hpa::LoadParams(hpa::DefaultParamsPath());
  return c;
}

// One World::Step at hover, sensor queues drained as the runner would.
void BM_WorldStep(benchmark::State& state) {
  hpa::sim::World world(Config());
  world.SetMotorSpeedCommand(
      hpa::InputVector::Constant(world.world_params().HoverMotorSpeedRadps()));
  std::vector<hpa::sim::SensorMessage> delivered;
  for (auto _ : state) {
    world.Step();
    world.TakeDelivered(&delivered);
  }
}
BENCHMARK(BM_WorldStep);

// Bare mj_step of the same model (no motors, sensors or checks).
void BM_MjStepBare(benchmark::State& state) {
  hpa::sim::World world(Config());
  for (auto _ : state)
    mj_step(hpa::sim::WorldInternals::Model(world), hpa::sim::WorldInternals::Data(world));
}
BENCHMARK(BM_MjStepBare);

// One 1280x720 payload camera frame (context created before timing).
void BM_RenderPayloadCamera(benchmark::State& state) {
  hpa::sim::World world(Config());
  world.renderer().RenderPayloadCamera();
  for (auto _ : state) {
    world.Step();
    benchmark::DoNotOptimize(world.renderer().RenderPayloadCamera().data);
  }
}
BENCHMARK(BM_RenderPayloadCamera)->Unit(benchmark::kMillisecond)->Iterations(50);

// One payload camera frame rendered in the region the runner asks for around the payload (the
// frustum narrowed to it), with the image model on that region.
void BM_RenderPayloadCameraRegion(benchmark::State& state) {
  hpa::sim::World world(Config());
  cv::Mat bgr;
  cv::Rect region;
  world.renderer().PayloadImageMotionPx(
      &region);              // the payload's image, grown for an off-axis sphere
  const int margin_px = 48;  // the runner's allowance for motion between frames
  region = cv::Rect(region.x - margin_px, region.y - margin_px, region.width + 2 * margin_px,
                    region.height + 2 * margin_px);
  world.renderer().RenderPayloadCamera(&bgr, region);
  for (auto _ : state) {
    world.Step();
    world.renderer().RenderPayloadCamera(&bgr, region);
    benchmark::DoNotOptimize(bgr.data);
  }
  state.counters["region_px"] = region.area();
}
BENCHMARK(BM_RenderPayloadCameraRegion)->Unit(benchmark::kMillisecond)->MinTime(1.0);

// The camera image model (lens distortion, PSF, noise) on a 232 x 232 sensor region of a
// 1280x720 frame: about the region around a payload 0.5 m below the camera (1.5 ball radii plus
// the runner's 48 px margin on each side); each iteration a new frame's noise.
void BM_CameraImageModelRegion(benchmark::State& state) {
  const hpa::Params params = hpa::LoadParams(hpa::DefaultParamsPath());
  hpa::sim::CameraImageProfile profile;
  profile.noise = true;
  hpa::sim::CameraImageModel model(params, profile, 1);
  cv::Mat pinhole(params.camera_height_px, params.camera_width_px, CV_8UC3);
  cv::randu(pinhole, 0, 256);
  const cv::Rect region(params.camera_width_px / 2 - 116, params.camera_height_px / 2 - 116, 232,
                        232);
  cv::Mat sensor;
  uint64_t frame = 0;
  model.ApplyOptics(pinhole, frame++, &sensor, region);  // tables and buffers before timing
  for (auto _ : state) {
    model.ApplyOptics(pinhole, frame++, &sensor, region);
    benchmark::DoNotOptimize(sensor.data);
  }
}
BENCHMARK(BM_CameraImageModelRegion)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
