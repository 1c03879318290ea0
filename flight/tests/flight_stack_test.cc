// The in-process FlightStack: commands at the controller's rate, the estimate from the sensors
// (or the truth), the estimate latency, the estimator health it reports and its camera path.

#include "hpa/flight/flight_stack.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "estimator/tests/synthetic_frames.h"
#include "hpa/models/camera_model.h"
#include "hpa/models/params.h"

namespace hpa::flight {
namespace {

constexpr double kTickHz = 1000.0;
constexpr double kDt_s = 1.0 / kTickHz;

// The shipped params without lens distortion: the synthetic frames are exact pinhole images.
Params TestParams() {
  Params params = LoadParams(DefaultParamsPath());
  params.camera_distortion.setZero();
  return params;
}

// Taut hover on the default reference (payload at 0.7 m, the vehicle a cable length above).
SystemState HoverState(const Params& params) {
  SystemState s;
  s.p_WL_W = ReferenceSpec().payload_position_W_m;
  s.p_WQ_W = s.p_WL_W + Eigen::Vector3d(0, 0, params.cable_length_m);
  return s;
}

FlightConfig HoverConfig(const std::string& controller) {
  FlightConfig c;
  c.params = TestParams();
  c.controller.type = controller;
  c.tick_hz = kTickHz;
  c.initial_state = HoverState(c.params);
  return c;
}

// Noise-free sensors of a vehicle hovering still at `truth` at tick `tick`: IMU at 500 Hz,
// VIO and payload detections at 30 Hz (stamped now, delivered at once).
FlightInputs HoverInputs(const Params& params, const SystemState& truth, long tick) {
  FlightInputs in;
  in.time_s = tick * kDt_s;
  if (tick % 2 == 0) {
    ImuSample imu;
    imu.time_s = in.time_s;
    imu.accel_B_mps2 = Eigen::Vector3d(0, 0, params.gravity_mps2);  // level, a = 0
    in.imu.push_back(imu);
  }
  if (tick % 33 == 0) {
    VioSample vio;
    vio.time_s = in.time_s;
    vio.p_WB_W = truth.p_WQ_W;
    in.vio.push_back(vio);
    PayloadDetection d;
    d.time_s = in.time_s;
    d.found = true;
    d.p_CL_C = PayloadInCamera_C(params, truth);
    d.centre_px = *ProjectToPixels(params, d.p_CL_C);
    d.radius_px = params.CameraFocalPx() * params.payload_radius_m / d.p_CL_C.z();
    in.detections.push_back(d);
  }
  in.allocation = AllocationReport{params.HoverThrustN(), false};
  return in;
}

TEST(FlightStackTest, HoverCommandsAtTheControllerRateWithAFiniteAccurateEstimate) {
  const FlightConfig config = HoverConfig("geometric");
  FlightStack stack(config);
  ASSERT_EQ(stack.control_rate_hz(), 150.0);
  const SystemState truth = HoverState(config.params);
  int commands = 0;
  for (long tick = 0; tick < 1000; ++tick) {
    const FlightOutputs out = stack.Step(HoverInputs(config.params, truth, tick));
    // the 150 Hz loop fires at the tick nearest k / 150 s
    const bool due = tick == std::llround(commands * kTickHz / 150.0);
    ASSERT_EQ(out.has_command, due) << "tick " << tick;
    // no latency and no need_estimate: the estimate is made exactly when the controller runs
    EXPECT_EQ(out.has_estimate, due) << "tick " << tick;
    if (!out.has_command) continue;
    ++commands;
    ASSERT_TRUE(out.estimate.AllFinite()) << "tick " << tick;
    EXPECT_EQ(out.estimate.time_s, tick * kDt_s);
    // noise-free sensors of a still vehicle: the estimate stays on the truth. Measured 0 (exact);
    // bound 1 cm, well under the 5 cm slack threshold, so a drifting filter fails it
    EXPECT_LT((out.estimate.p_WQ_W - truth.p_WQ_W).norm(), 0.01) << "tick " << tick;
    EXPECT_LT((out.estimate.p_WL_W - truth.p_WL_W).norm(), 0.01) << "tick " << tick;
    EXPECT_EQ(out.estimate.mode, CableMode::kTaut);
    // at rest on the reference the controller holds the weight of vehicle + payload. Measured
    // exact; 0.1 % leaves room only for rounding and a sub-millimetre estimate error
    EXPECT_NEAR(out.command.command.thrust_N, config.params.HoverThrustN(),
                1e-3 * config.params.HoverThrustN());
    EXPECT_LT(out.command.command.w_B_radps.norm(), 1e-3);  // rad/s: measured 0, level
    EXPECT_EQ(out.estimator_rejected_updates, 0);
    EXPECT_EQ(out.estimator_resets, 0);
  }
  EXPECT_EQ(commands, 150);  // one second at 150 Hz: k = 0..149
  EXPECT_FALSE(stack.EstimatorHealth().empty());
}

TEST(FlightStackTest, NeedEstimateGivesAnEstimateBetweenControlTicks) {
  const FlightConfig config = HoverConfig("geometric");
  FlightStack stack(config);
  const SystemState truth = HoverState(config.params);
  ASSERT_TRUE(stack.Step(HoverInputs(config.params, truth, 0)).has_command);
  FlightInputs in = HoverInputs(config.params, truth, 1);  // tick 1: not a 150 Hz tick
  in.need_estimate = true;
  const FlightOutputs out = stack.Step(in);
  EXPECT_FALSE(out.has_command);
  EXPECT_TRUE(out.has_estimate);
  EXPECT_EQ(out.estimate.time_s, kDt_s);
  EXPECT_TRUE(out.estimate.AllFinite());
}

TEST(FlightStackTest, UnknownNamesAreRefused) {
  FlightConfig bad_estimator = HoverConfig("geometric");
  bad_estimator.estimator = "no_such_estimator";
  EXPECT_THROW(FlightStack{bad_estimator}, std::invalid_argument);
  EXPECT_THROW(FlightStack{HoverConfig("no_such_controller")}, std::invalid_argument);
}

TEST(FlightStackTest, GroundTruthIsTheEstimateAndHasNoHealth) {
  FlightConfig config = HoverConfig("geometric");
  config.ground_truth = true;
  FlightStack stack(config);
  SystemState truth = HoverState(config.params);
  truth.p_WQ_W.x() += 0.123;  // off the initial state: an estimator would not report this
  truth.time_s = -5.0;        // relabelled with the tick's time
  FlightInputs in;
  in.time_s = 0.0;
  in.truth = truth;
  const FlightOutputs out = stack.Step(in);
  ASSERT_TRUE(out.has_command);
  ASSERT_TRUE(out.has_estimate);
  EXPECT_EQ(out.estimate.p_WQ_W, truth.p_WQ_W);
  EXPECT_EQ(out.estimate.p_WL_W, truth.p_WL_W);
  EXPECT_EQ(out.estimate.time_s, 0.0);
  EXPECT_TRUE(stack.EstimatorHealth().empty());
  EXPECT_EQ(out.estimator_rejected_updates, 0);
  EXPECT_TRUE(out.camera_roi.empty());  // no detector with ground truth
}

TEST(FlightStackTest, GroundTruthWithoutTruthAtAControlTickThrows) {
  FlightConfig config = HoverConfig("geometric");
  config.ground_truth = true;
  FlightStack stack(config);
  FlightInputs in;  // tick 0 is a control tick
  EXPECT_THROW(stack.Step(in), std::invalid_argument);
}

// Truth moving along x at 1 m/s (vehicle and payload together), for the latency test.
SystemState MovingTruth(const Params& params, double t_s) {
  SystemState s = HoverState(params);
  s.p_WL_W.x() += t_s;
  s.p_WQ_W.x() += t_s;
  s.v_WL_W.x() = 1.0;
  s.v_WQ_W.x() = 1.0;
  return s;
}

TEST(FlightStackTest, EstimateLatencyFeedsTheControllerTheEstimateThatOld) {
  constexpr double kLatency_s = 0.01;  // ten ticks
  FlightConfig delayed_config = HoverConfig("geometric");
  delayed_config.ground_truth = true;
  delayed_config.estimate_latency_s = kLatency_s;
  FlightConfig fresh_config = delayed_config;
  fresh_config.estimate_latency_s = 0.0;
  FlightStack delayed(delayed_config), by_hand(fresh_config), fresh(fresh_config);
  const Params& params = delayed_config.params;
  int commands = 0, differing = 0;
  for (long tick = 0; tick < 100; ++tick) {
    const double t_s = tick * kDt_s;
    FlightInputs in;
    in.time_s = t_s;
    in.truth = MovingTruth(params, t_s);
    const FlightOutputs out = delayed.Step(in);
    const FlightOutputs now = fresh.Step(in);
    // by hand: the truth of ten ticks ago (the current one until there is one that old)
    in.truth = MovingTruth(params, tick >= 10 ? (tick - 10) * kDt_s : t_s);
    const FlightOutputs expected = by_hand.Step(in);
    // with a latency the estimate is made every tick, and reported current
    ASSERT_TRUE(out.has_estimate);
    EXPECT_NEAR(out.estimate.p_WQ_W.x(), MovingTruth(params, t_s).p_WQ_W.x(), 1e-12);
    ASSERT_EQ(out.has_command, expected.has_command);
    if (!out.has_command) continue;
    ++commands;
    // the same controller on the same numbers: bit for bit
    EXPECT_EQ(out.command.command.thrust_N, expected.command.command.thrust_N) << "tick " << tick;
    EXPECT_EQ(out.command.command.w_B_radps, expected.command.command.w_B_radps) << "tick " << tick;
    if (tick >= 10 && out.command.command.w_B_radps != now.command.command.w_B_radps) ++differing;
  }
  EXPECT_EQ(commands, 15);  // 0.1 s at 150 Hz
  // the 1 cm the vehicle moves in 10 ms changes the command: the comparison above has teeth
  EXPECT_GT(differing, 0);
}

TEST(FlightStackTest, GatedVioOutlierShowsInTheReportedHealth) {
  const FlightConfig config = HoverConfig("geometric");
  FlightStack stack(config);
  const SystemState truth = HoverState(config.params);
  long tick = 0;
  for (; tick < 300; ++tick) {
    ASSERT_EQ(stack.Step(HoverInputs(config.params, truth, tick)).estimator_rejected_updates, 0);
  }
  // 5 m off after 0.3 s of consistent VIO: far over the quad filter's NIS gate of 50
  FlightInputs in = HoverInputs(config.params, truth, tick);
  VioSample outlier;
  outlier.time_s = in.time_s;
  outlier.p_WB_W = truth.p_WQ_W + Eigen::Vector3d(5.0, 0, 0);
  in.vio = {outlier};
  const FlightOutputs out = stack.Step(in);
  EXPECT_EQ(out.estimator_rejected_updates, 1);
  EXPECT_EQ(out.estimator_resets, 0);
  int found = 0;
  for (const auto& [name, value] : stack.EstimatorHealth()) {
    if (name == "rejected_updates" || name == "quad_rejected_updates") {
      EXPECT_EQ(value, 1.0) << name;
      ++found;
    }
  }
  EXPECT_EQ(found, 2);
}

TEST(FlightStackTest, CameraFramesAreDetectedAndSetTheNextRegion) {
  const FlightConfig config = HoverConfig("geometric");
  FlightStack stack(config);
  const SystemState truth = HoverState(config.params);
  const Eigen::Vector3d p_CL_C = PayloadInCamera_C(config.params, truth);
  ASSERT_GT(p_CL_C.z(), 0.0);
  CameraFrame frame;
  frame.whole_bgr = testing_frames::RenderSphere(config.params, p_CL_C);
  FlightInputs in = HoverInputs(config.params, truth, 0);
  in.frames = {frame};
  const FlightOutputs seen = stack.Step(in);
  EXPECT_EQ(seen.frames_detected, 1);
  // the next read-out is around the ball's image
  const Eigen::Vector2d centre_px = *ProjectToPixels(config.params, p_CL_C);
  ASSERT_FALSE(seen.camera_roi.empty());
  EXPECT_TRUE(seen.camera_roi.contains(
      cv::Point(static_cast<int>(centre_px.x()), static_cast<int>(centre_px.y()))));
  EXPECT_LT(seen.camera_roi.area(), frame.whole_bgr.cols * frame.whole_bgr.rows);

  // an empty floor: nothing found, so the whole frame is read next
  CameraFrame empty;
  empty.whole_bgr = testing_frames::RenderSphere(config.params, Eigen::Vector3d(0, 0, -1.0));
  in = HoverInputs(config.params, truth, 1);
  in.frames = {empty};
  const FlightOutputs missed = stack.Step(in);
  EXPECT_EQ(missed.frames_detected, 0);
  EXPECT_TRUE(missed.camera_roi.empty());
}

TEST(FlightStackTest, DeliveredDetectionsSetTheNextRegion) {
  // the camera's detections (the analytic camera's, or made at capture in process) steer the
  // region of interest as the stack's own detections in frames do
  const FlightConfig config = HoverConfig("geometric");
  FlightStack stack(config);
  const PayloadDetector detector(config.params);
  const SystemState truth = HoverState(config.params);
  const Eigen::Vector3d p_CL_C = PayloadInCamera_C(config.params, truth);
  const PayloadDetection d =
      detector.Detect(testing_frames::RenderSphere(config.params, p_CL_C), 0.0);
  ASSERT_TRUE(d.found) << d.reason;
  FlightInputs in = HoverInputs(config.params, truth, 0);
  in.detections = {d};
  const FlightOutputs seen = stack.Step(in);
  EXPECT_EQ(seen.frames_detected, 0);  // a detection is not a frame
  EXPECT_EQ(seen.camera_roi, detector.RegionAround({PayloadDetection(), d}, kRegionMarginPx));
  ASSERT_FALSE(seen.camera_roi.empty());
}

TEST(FlightStackTest, DetectFrameFallsBackToTheWholeFrame) {
  const Params params = TestParams();
  const PayloadDetector detector(params);
  const Eigen::Vector3d p_CL_C(0.0, 0.0, 0.45);
  CameraFrame frame;
  frame.capture_time_s = 2.5;
  frame.whole_bgr = testing_frames::RenderSphere(params, p_CL_C);
  // a region far from the ball, read out as empty floor: it cannot hold the payload
  frame.region = cv::Rect(0, 0, 64, 64);
  frame.region_bgr = testing_frames::RenderSphere(params, Eigen::Vector3d(0, 0, -1.0));
  const PayloadDetection d = DetectFrame(detector, frame);
  ASSERT_TRUE(d.found) << d.reason;
  EXPECT_EQ(d.time_s, 2.5);
  // 3 mm: the detector's bound on exact synthetic frames (payload_detector_test.cc)
  EXPECT_LT((d.p_CL_C - p_CL_C).norm(), 3e-3);
}

TEST(FlightStackTest, DetectFrameReadsTheWholeFrameOnlyWhenTheRegionCannotDecide) {
  // the in-process camera's frame holds its region alone and renders the whole frame on request
  const Params params = TestParams();
  const PayloadDetector detector(params);
  const Eigen::Vector3d p_CL_C(0.0, 0.0, 0.45);
  const cv::Mat whole = testing_frames::RenderSphere(params, p_CL_C);
  int reads = 0;
  const WholeFrameReader read_whole = [&]() -> const cv::Mat& {
    ++reads;
    return whole;
  };
  const PayloadDetection expected = detector.Detect(whole, 1.0);
  ASSERT_TRUE(expected.found) << expected.reason;
  RecentDetections recent;
  recent.Push(expected);

  // a region around the ball decides alone, with the whole frame's result
  CameraFrame around;
  around.capture_time_s = 1.0;
  around.region = detector.RegionAround(recent, kRegionMarginPx);
  around.region_bgr = whole;
  const PayloadDetection in_region = DetectFrame(detector, around, read_whole);
  EXPECT_EQ(reads, 0);
  EXPECT_EQ(in_region.centre_px, expected.centre_px);

  // a region of empty floor cannot: the whole frame is read out once
  CameraFrame away;
  away.capture_time_s = 1.0;
  away.region = cv::Rect(0, 0, 64, 64);
  away.region_bgr = testing_frames::RenderSphere(params, Eigen::Vector3d(0, 0, -1.0));
  const PayloadDetection fallen_back = DetectFrame(detector, away, read_whole);
  EXPECT_EQ(reads, 1);
  EXPECT_EQ(fallen_back.centre_px, expected.centre_px);
}

TEST(FlightStackTest, ControlThreadGivesTheCallersThreadsCommandsInOrder) {
  // hpa_mpc from a displaced start (its plan moves every step); the threaded stack's commands
  // are taken in batches of up to seven, so that more are pending than its ring first holds
  FlightConfig config = HoverConfig("hpa_mpc");
  config.initial_state.p_WQ_W += Eigen::Vector3d(0.05, -0.03, 0.02);
  config.initial_state.p_WL_W += Eigen::Vector3d(0.05, -0.03, 0.02);
  FlightStack inline_stack(config);
  config.control_thread = true;
  FlightStack threaded_stack(config);
  EXPECT_THROW(threaded_stack.AwaitCommand(), std::logic_error);
  EXPECT_THROW(inline_stack.AwaitCommand(), std::logic_error);
  const SystemState truth = HoverState(config.params);
  std::vector<ControlOutput> expected;
  int taken = 0, pending = 0, batch = 1;
  const auto take = [&] {
    for (; pending > 0; --pending, ++taken) {
      const ControlOutput got = threaded_stack.AwaitCommand();
      ASSERT_LT(taken, static_cast<int>(expected.size()));
      const ControlOutput& want = expected[taken];
      EXPECT_EQ(got.command.w_B_radps, want.command.w_B_radps) << "command " << taken;
      EXPECT_EQ(got.command.thrust_N, want.command.thrust_N) << "command " << taken;
      EXPECT_EQ(got.status, want.status) << "command " << taken;
      EXPECT_EQ(got.cost, want.cost) << "command " << taken;
    }
  };
  for (long tick = 0; tick < 400; ++tick) {
    const FlightInputs in = HoverInputs(config.params, truth, tick);
    const FlightOutputs a = inline_stack.Step(in);
    const FlightOutputs b = threaded_stack.Step(in);
    ASSERT_EQ(a.has_command, b.has_command) << "tick " << tick;
    EXPECT_FALSE(a.command_pending);
    EXPECT_EQ(b.command_pending, b.has_command);
    EXPECT_EQ(a.estimate.p_WL_W, b.estimate.p_WL_W) << "tick " << tick;
    if (a.has_command) {
      expected.push_back(a.command);
      ++pending;
    }
    if (pending == batch) {
      take();
      batch = batch % 7 + 1;  // 1, 2, ..., 7, 1, ...
    }
  }
  take();
  EXPECT_EQ(taken, 60);  // 150 Hz for 0.4 s
  EXPECT_THROW(threaded_stack.AwaitCommand(), std::logic_error);
}

}  // namespace
}  // namespace hpa::flight
