// Cost of the simulated world: one 1 ms physics step (motors, sensors, crash check, mj_step) and
// one 1280x720 payload camera frame (OSMesa llvmpipe, shadows/reflection/skybox off).
#include <benchmark/benchmark.h>

#include "hpa/models/params.h"
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
  for (auto _ : state) {
    world.Step();
    while (world.TakeImu()) {
    }
    while (world.TakeVio()) {
    }
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
  world.RenderPayloadCamera();
  for (auto _ : state) {
    world.Step();
    benchmark::DoNotOptimize(world.RenderPayloadCamera().data);
  }
}
BENCHMARK(BM_RenderPayloadCamera)->Unit(benchmark::kMillisecond)->Iterations(50);

}  // namespace

BENCHMARK_MAIN();
