// `hpa render-frame`: the scenario run to a time and one camera frame of it written as a PNG,
// the onboard payload camera's or the videos' chase camera's, at its own size or a given one.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <string>

#include "hpa/controller/controller_registry.h"
#include "hpa/models/input_error.h"
#include "hpa/models/params.h"
#include "hpa/scenarios/runner.h"
#include "hpa/scenarios/scenario.h"
#include "hpa/scenarios/video_recorder.h"
#include "hpa/sim/world.h"
#include "harness/reports/src/media.h"
#include "harness/cli/src/cli_parse.h"
#include "harness/cli/src/scenario_command_common.h"
#include "harness/cli/src/scenario_commands.h"

namespace hpa {
namespace {

// Refuses an --out that is no FILE.png and a --camera that is neither payload nor chase.
void CheckFrameArguments(const std::string& out, const std::string& camera) {
  if (out.size() < 5 || out.compare(out.size() - 4, 4, ".png") != 0) {
    throw InputError("", "--out",
                     "the frame is written as PNG: give a FILE.png, got '" + out + "'");
  }
  if (camera != "payload" && camera != "chase") {
    throw InputError("", "--camera", "expected payload | chase, got '" + camera + "'");
  }
}

// The frame's size in pixels: --size (WxH) if given, else the chase camera's the videos' and the
// payload camera's its own (0 x 0).
void FrameSize(const std::string& size, bool chase, int* width_px, int* height_px) {
  // the chase camera's size is the videos'; a side beyond 4096 px is no frame anyone looks at
  constexpr int kMinSide_px = 16, kMaxSide_px = 4096;
  *width_px = chase ? VideoRecorder::kWidthPx : 0;  // 0: the payload camera's own
  *height_px = chase ? VideoRecorder::kHeightPx : 0;
  if (!size.empty()) {
    char tail = 0;
    if (std::sscanf(size.c_str(), "%dx%d%c", width_px, height_px, &tail) != 2 ||
        *width_px < kMinSide_px || *width_px > kMaxSide_px || *height_px < kMinSide_px ||
        *height_px > kMaxSide_px) {
      throw InputError("", "--size", "expected WxH with each side 16-4096 px, got '" + size + "'");
    }
  }
}

// The camera's frame of the world now, scaled to width_px x height_px (0: as rendered).
cv::Mat RenderFrame(sim::World& world, bool chase, int width_px, int height_px) {
  cv::Mat frame;
  if (chase) {
    // the offscreen buffer bounds a render (Renderer::RenderChaseCamera: at most 1280x720): a
    // larger frame is scaled up from the largest render of its aspect that fits
    constexpr double kMaxRenderWidth_px = 1280.0, kMaxRenderHeight_px = 720.0;
    const double fit =
        std::min({1.0, kMaxRenderWidth_px / width_px, kMaxRenderHeight_px / height_px});
    frame = world.renderer().RenderChaseCamera(std::max(1, static_cast<int>(width_px * fit)),
                                               std::max(1, static_cast<int>(height_px * fit)));
  } else {
    frame = world.renderer().RenderPayloadCamera();
  }
  if (width_px > 0 && (frame.cols != width_px || frame.rows != height_px)) {
    cv::Mat scaled;
    cv::resize(frame, scaled, cv::Size(width_px, height_px), 0, 0,
               frame.cols > width_px ? cv::INTER_AREA : cv::INTER_LINEAR);
    frame = scaled;
  }
  return frame;
}

}  // namespace

int RenderFrameMain(int argc, char** argv) {
  ScenarioOptions o;
  std::string out, controller, camera = "payload", size;
  double at_s = 0.0;
  CLI::App app{
      "Runs the scenario to time T and writes one camera frame (PNG): the onboard payload "
      "camera, or the videos' chase camera.",
      "hpa render-frame"};
  AddScenarioOptions(app, &o, false, false);
  app.add_option("--at", at_s, "time T [s] in [0, duration]")->required();
  app.add_option("--out", out, "FILE.png")->required();
  app.add_option("--controller", controller, "a registered controller (see hpa --help)");
  app.add_option("--camera", camera, "payload (the onboard camera, default) | chase");
  app.add_option("--size", size,
                 "WxH pixels, each side 16-4096 (default: the camera's own size; payload "
                 "1280x720, chase 960x540)");
  if (const auto code = ParseCommandLine(app, argc, argv)) return *code;
  CheckFrameArguments(out, camera);
  const bool chase = camera == "chase";
  int width_px = 0, height_px = 0;
  FrameSize(size, chase, &width_px, &height_px);
  const Params params = LoadParamsOf(o);
  Scenario scenario = LoadScenarioOf(o);
  if (!controller.empty()) {
    CheckControllerType(controller, "", "--controller");
    scenario.controller.type = controller;
  }
  if (!std::isfinite(at_s) || at_s < 0 || at_s > scenario.duration_s) {
    throw InputError("", "--at", "expected a time in [0, duration] of the scenario");
  }
  RunOptions options;
  options.stop_at_s = at_s;
  options.gl_backend = ParseGlOption(o.gl);
  bool written = false;
  std::optional<OutputError> write_error;  // the media module could not be loaded
  double frame_time_s = at_s;
  options.at_stop = [&](sim::World& world) {
    frame_time_s = world.time_s();
    const cv::Mat frame = RenderFrame(world, chase, width_px, height_px);
    try {
      written = WriteImage(out, frame);  // false for an extension OpenCV cannot encode too
    } catch (const OutputError& e) {
      write_error = e;
    }
  };
  const RunResult result = RunScenario(scenario, params, options);
  if (result.metrics.run_error) {
    std::fprintf(stderr, "hpa: internal error during the run: %s\n",
                 result.metrics.run_error->c_str());
    return kExitInternal;
  }
  if (write_error) throw *write_error;
  if (!written) throw OutputError(out, "the PNG could not be written (does its folder exist?)");
  if (result.metrics.crashed) {
    std::printf("note: the vehicle crashed at t = %.3f s (%s); the frame is from then\n",
                frame_time_s, result.metrics.crash_reason.value_or("").c_str());
  }
  std::printf("wrote %s (%s camera at t = %.3f s)\n", out.c_str(), camera.c_str(), frame_time_s);
  return kExitOk;
}

}  // namespace hpa
