// Detector accuracy on frames rendered by the simulator (MuJoCo 2.2 + OSMesa): payload placed at
// many camera-frame positions (centre, off-centre, near the edge, partly out of view), position
// error statistics against ground truth, frames without the payload, and ms per detection.
// These measurements are the source of CameraNoiseModel's defaults (detection_noise.h).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "hpa/estimator/payload_detector.h"
#include "hpa/models/camera_model.h"
#include "hpa/models/params.h"
#include "hpa/sim/analytic_camera.h"
#include "hpa/sim/world.h"
#include "models/tests/temp_dir.h"

namespace hpa {
namespace {

// Per-axis error statistics of one image region.
struct AxisStats {
  std::vector<Eigen::Vector3d> errors;
  std::vector<double> centre_errors_px;      // ellipse centre vs exact, per image axis
  std::vector<double> semi_major_errors_px;  // implied by the range error
  Eigen::Vector3d Mean() const {
    Eigen::Vector3d m = Eigen::Vector3d::Zero();
    for (const auto& e : errors) m += e;
    return m / std::max<size_t>(1, errors.size());
  }
  Eigen::Vector3d Std() const {
    const Eigen::Vector3d m = Mean();
    Eigen::Vector3d s = Eigen::Vector3d::Zero();
    for (const auto& e : errors) s += (e - m).cwiseAbs2();
    return (s / std::max<size_t>(1, errors.size())).cwiseSqrt();
  }
  Eigen::Vector3d Max() const {
    Eigen::Vector3d m = Eigen::Vector3d::Zero();
    for (const auto& e : errors) m = m.cwiseMax(e.cwiseAbs());
    return m;
  }
};

double MeanOf(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s / std::max<size_t>(1, v.size());
}
double StdOf(const std::vector<double>& v) {
  const double m = MeanOf(v);
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / std::max<size_t>(1, v.size()));
}

// What the detector did over a grid of rendered payload positions.
struct Survey {
  std::map<std::string, AxisStats> regions;  // errors by where the exact ellipse lies
  int frames = 0;                            // rendered frames
  int must_miss = 0;                         // frames with too little of the payload in view
  int missed = 0;                            // of those, the frames without a detection
  int lost_visible = 0;                      // fully inside the image but not detected
  int region_tried = 0;                      // detections whose region around was tried
  int region_decided = 0;                    // of those, the regions that decided
  double detect_ms = 0.0;                    // total time in Detect
};

// Where the exact ellipse lies in the image: partly out of view, near the edge (within 2.5 radii),
// at the centre (within 35 % of the half size) or off-centre.
std::string RegionOf(const PayloadDetection& ideal, double visible, double half_w, double half_h) {
  const Eigen::Vector2d c = ideal.centre_px;
  const double edge_px = std::min({c.x(), 2 * half_w - c.x(), c.y(), 2 * half_h - c.y()});
  const double off_axis =
      std::max(std::abs(c.x() - half_w) / half_w, std::abs(c.y() - half_h) / half_h);
  return visible < 1.0                     ? "partly out"
         : edge_px < 2.5 * ideal.radius_px ? "near edge"
         : off_axis < 0.35                 ? "centre"
                                           : "off-centre";
}

// With EST_DUMP set, writes the first frames to the test's temporary folder and prints the true
// and detected payload positions, to look at what the detector saw.
void MaybeDumpFrame(int frames, const cv::Mat& frame, const PayloadDetection& d,
                    const Eigen::Vector3d& true_C) {
  if (!std::getenv("EST_DUMP") || frames >= 200) return;
  char file[64];
  std::snprintf(file, sizeof(file), "est_frame_%03d_%s.png", frames, d.found ? "found" : "lost");
  const std::string name = TestTempDir() + file;
  cv::imwrite(name, frame);
  std::printf("%s: true %.0f %.0f %.0f det %.0f %.0f %.0f mm, %s\n", name.c_str(), 1e3 * true_C.x(),
              1e3 * true_C.y(), 1e3 * true_C.z(), 1e3 * d.p_CL_C.x(), 1e3 * d.p_CL_C.y(),
              1e3 * d.p_CL_C.z(), d.reason.c_str());
}

// Prints each region's error statistics and collects the fully visible regions' centre and
// semi-major errors into *all_centre and *all_axis.
void PrintRegions(const std::map<std::string, AxisStats>& regions, std::vector<double>* all_centre,
                  std::vector<double>* all_axis) {
  for (const auto& [name, s] : regions) {
    const Eigen::Vector3d m = 1e3 * s.Mean(), sd = 1e3 * s.Std(), mx = 1e3 * s.Max();
    std::printf(
        "%-10s n=%3zu  mean [%5.2f %5.2f %5.2f] std [%5.2f %5.2f %5.2f] "
        "max [%5.2f %5.2f %5.2f] mm",
        name.c_str(), s.errors.size(), m.x(), m.y(), m.z(), sd.x(), sd.y(), sd.z(), mx.x(), mx.y(),
        mx.z());
    if (!s.centre_errors_px.empty()) {
      std::printf("  centre %.2f+-%.2f px, semi-major %.2f+-%.2f px", MeanOf(s.centre_errors_px),
                  StdOf(s.centre_errors_px), MeanOf(s.semi_major_errors_px),
                  StdOf(s.semi_major_errors_px));
      all_centre->insert(all_centre->end(), s.centre_errors_px.begin(), s.centre_errors_px.end());
      all_axis->insert(all_axis->end(), s.semi_major_errors_px.begin(),
                       s.semi_major_errors_px.end());
    }
    std::printf("\n");
  }
}

class RenderedDetectorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    sim::WorldConfig config;
    config.params = LoadParams(DefaultParamsPath());
    // the flight profile's camera: lens distortion, PSF, the cable in view, shot and read noise,
    // and motion blur of a payload swinging at 0.5 m/s across the view
    config.profile.camera.noise = true;
    config.profile.camera.analog_gain = 4.0;
    config.profile.camera.exposure_s = 0.005;
    params_ = config.params;
    world_ = std::make_unique<sim::World>(config);
  }

  // Places the quadrotor at 1.5 m with attitude q_WB and the payload at p_CL_C in its camera.
  cv::Mat RenderAt(const Eigen::Vector3d& p_CL_C, const Eigen::Quaterniond& q_WB,
                   SystemState* truth) {
    SystemState s;
    s.p_WQ_W = Eigen::Vector3d(0.2, -0.1, 1.5);
    s.q_WB = q_WB;
    const Eigen::Matrix3d R_WB = q_WB.toRotationMatrix();
    s.p_WL_W = s.p_WQ_W + R_WB * (params_.t_BC_B_m + params_.R_BC * p_CL_C);
    s.v_WL_W = Eigen::Vector3d(0.3, 0.4, 0.0);
    world_->SetState(s.ToVector(), InputVector::Constant(params_.HoverMotorSpeedRadps()));
    *truth = world_->GetTruth().state;
    return world_->renderer().RenderPayloadCamera();
  }

  // Renders the payload at p_CL_C (attitude q_WB), detects it, checks a region around the
  // detection gives the same, and adds its error to the region where the exact ellipse lies.
  void SurveyFrame(const PayloadDetector& detector, const sim::AnalyticCamera& exact,
                   std::mt19937_64& rng, const Eigen::Vector3d& p_CL_C,
                   const Eigen::Quaterniond& q_WB, Survey* survey) {
    SystemState truth;
    const cv::Mat frame = RenderAt(p_CL_C, q_WB, &truth);
    const Eigen::Vector3d true_C = PayloadInCamera_C(params_, truth);
    ++survey->frames;
    const auto start = std::chrono::steady_clock::now();
    const PayloadDetection d = detector.Detect(frame, 0.0);
    survey->detect_ms +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    const double visible = VisibleOutlineFraction(
        params_, SphereOutlinePx(params_, true_C, params_.payload_radius_m, 360));
    if (visible < detector.config().min_visible_outline - 0.1) {
      ++survey->must_miss;
      EXPECT_FALSE(d.found) << "visible " << visible << " at " << true_C.transpose();
      survey->missed += !d.found;
      return;
    }
    MaybeDumpFrame(survey->frames, frame, d, true_C);
    if (!d.found) {
      // fully inside the image but lost: the cable near the lens covers the ball
      if (visible >= 1.0) ++survey->lost_visible;
      return;
    }
    // the region around this detection gives exactly this detection whenever it decides
    RecentDetections recent;
    recent.Push(d);
    const cv::Rect around = detector.RegionAround(recent, 48.0);
    if (const auto in_region = detector.DetectInRegion(frame, around, 0.0)) {
      ++survey->region_decided;
      EXPECT_EQ(in_region->p_CL_C, d.p_CL_C) << "region " << around;
      EXPECT_EQ(in_region->centre_px, d.centre_px);
      EXPECT_EQ(in_region->radius_px, d.radius_px);
    }
    ++survey->region_tried;
    // region by where the exact ellipse lies
    const PayloadDetection ideal = exact.Measure(true_C, 0.0, rng);
    const double f_px = params_.CameraFocalPx();
    const std::string region =
        RegionOf(ideal, visible, 0.5 * params_.camera_width_px, 0.5 * params_.camera_height_px);
    AxisStats& stats = survey->regions[region];
    stats.errors.push_back(d.p_CL_C - true_C);
    if (region == "partly out") return;
    stats.centre_errors_px.push_back(d.centre_px.x() - ideal.centre_px.x());
    stats.centre_errors_px.push_back(d.centre_px.y() - ideal.centre_px.y());
    const double D = true_C.norm();
    const double cos2 = std::pow(true_C.z() / D, 2);
    stats.semi_major_errors_px.push_back(-(d.p_CL_C.norm() - D) * f_px * params_.payload_radius_m *
                                         cos2 / (D * D));
  }

  Params params_;
  std::unique_ptr<sim::World> world_;
};

TEST_F(RenderedDetectorTest, ErrorStatisticsByRegion) {
  const PayloadDetector detector(params_);
  const sim::AnalyticCamera exact(params_, CameraNoiseModel{0.0, 0.0, 0.0, 0.0});
  std::mt19937_64 rng(1);  // unused by the noiseless camera
  const double f_px = params_.CameraFocalPx();
  const double half_w = 0.5 * params_.camera_width_px, half_h = 0.5 * params_.camera_height_px;
  Survey survey;
  const Eigen::Quaterniond tilted(Eigen::AngleAxisd(0.15, Eigen::Vector3d(1, 2, 0).normalized()));
  // image positions as fractions of the half width/height, distances from the camera
  for (double distance_m : {0.25, 0.35, 0.45}) {
    for (double fx : {-1.02, -0.9, -0.6, -0.25, 0.0, 0.3, 0.65, 0.85, 0.97}) {
      for (double fy : {-0.9, -0.3, 0.0, 0.5, 0.95}) {
        const Eigen::Vector3d ray((fx * half_w) / f_px, (fy * half_h) / f_px, 1.0);
        const Eigen::Vector3d p_CL_C = distance_m * ray.normalized();
        const Eigen::Quaterniond q =
            (survey.frames % 2 == 0) ? Eigen::Quaterniond::Identity() : tilted;
        SurveyFrame(detector, exact, rng, p_CL_C, q, &survey);
      }
    }
  }
  std::map<std::string, AxisStats>& regions = survey.regions;
  std::printf("rendered frames: %d, %d out of view (all missed: %d), mean detection %.2f ms\n",
              survey.frames, survey.must_miss, survey.missed, survey.detect_ms / survey.frames);
  std::vector<double> all_centre, all_axis;
  PrintRegions(regions, &all_centre, &all_axis);
  std::printf("fully visible: centre error %.3f +- %.3f px, semi-major error %.3f +- %.3f px\n",
              MeanOf(all_centre), StdOf(all_centre), MeanOf(all_axis), StdOf(all_axis));
  // detection rate over fully visible frames: measured 82 of 94 (the 12 lost are covered by the
  // cable); at least 0.80 (twice the measured loss fails)
  int fully_visible_found = 0;
  for (const char* name : {"centre", "off-centre", "near edge"}) {
    fully_visible_found += static_cast<int>(regions[name].errors.size());
  }
  const double detection_rate =
      static_cast<double>(fully_visible_found) / (fully_visible_found + survey.lost_visible);
  std::printf("detection rate, fully visible: %.3f (%d lost)\n", detection_rate,
              survey.lost_visible);
  EXPECT_GE(detection_rate, 0.80);
  // regions decide most frames (those they do not are detected on the whole frame): measured
  // 95 of 102; at least 85 %
  std::printf("regions around the detection decided %d of %d frames\n", survey.region_decided,
              survey.region_tried);
  EXPECT_GE(survey.region_decided, 0.85 * survey.region_tried);
  EXPECT_EQ(survey.missed, survey.must_miss);
  ASSERT_TRUE(regions.count("centre") && regions.count("off-centre") && regions.count("near edge"));
  // bounds 2x above the measured maxima (1.81 mm lateral, 4.35 mm along z over the fully
  // visible regions; 2.50 mm partly out of view), so a regression of the fit, of the occluder
  // handling, of the undistortion or of the geometry fails
  for (const char* name : {"centre", "off-centre", "near edge"}) {
    const Eigen::Vector3d mx = regions[name].Max();
    EXPECT_LT(mx.head<2>().maxCoeff(), 0.0036) << name;
    EXPECT_LT(mx.z(), 0.0087) << name;
  }
  if (regions.count("partly out")) {
    EXPECT_LT(regions["partly out"].Max().maxCoeff(), 0.005);
  }
  // the analytic camera's noise model is this measurement (detection_noise.h): it must stay
  // within 0.03 px of it
  const CameraNoiseModel model = MeasuredDetectorNoise();
  EXPECT_NEAR(StdOf(all_centre), model.centre_std_px, 0.03);
  EXPECT_NEAR(StdOf(all_axis), model.semi_major_std_px, 0.03);
  EXPECT_NEAR(MeanOf(all_axis), model.semi_major_bias_px, 0.03);
}

TEST_F(RenderedDetectorTest, NoDetectionWithoutThePayload) {
  const PayloadDetector detector(params_);
  // payload above the camera (behind it) and far to the side: the frame shows floor only
  for (const Eigen::Vector3d& p_CL_C :
       {Eigen::Vector3d(0, 0, -0.3), Eigen::Vector3d(2.0, 0, 0.3)}) {
    SystemState truth;
    const cv::Mat frame = RenderAt(p_CL_C, Eigen::Quaterniond::Identity(), &truth);
    const PayloadDetection d = detector.Detect(frame, 0.0);
    EXPECT_FALSE(d.found) << "at " << p_CL_C.transpose();
  }
}

}  // namespace
}  // namespace hpa
