// The onboard estimator in steady state allocates no heap memory: fed at the flight rates (IMU
// 500 Hz, VIO 30 Hz arriving 20 ms late, detections 30 Hz arriving 30 ms late, the allocated
// thrust, the estimate read at 150 Hz), every variant, taut and slack. Its own binary: global
// operator new is replaced by a counting one (models/tests/support/counting_allocator.h).

#include <gtest/gtest.h>

#include <cmath>
#include <deque>
#include <string>

#include "hpa/estimator/estimator_registry.h"
#include "hpa/models/camera_model.h"
#include "hpa/models/params.h"
#include "models/tests/support/counting_allocator.h"

namespace hpa {
namespace {

using test_support::CountAllocations;

// Feeds `estimator` a hovering vehicle whose payload hangs `cable_m` below it, from t0_s for
// duration_s, at the flight rates; late messages are held in queues the caller owns (sized before
// counting starts).
class HoverFeed {
 public:
  HoverFeed(const Params& params, Estimator* estimator) : params_(params), estimator_(estimator) {}

  void Fly(double t0_s, double duration_s, double cable_m) {
    const int first = static_cast<int>(std::lround(t0_s * 3000.0));
    const int last = static_cast<int>(std::lround((t0_s + duration_s) * 3000.0));
    // a 3 kHz clock: IMU every 6th tick, estimate every 20th, camera and VIO every 100th
    for (int tick = first; tick < last; ++tick) {
      const double t_s = tick / 3000.0;
      truth_.time_s = t_s;
      truth_.p_WQ_W = Eigen::Vector3d(0, 0, 1.0);
      truth_.p_WL_W = truth_.p_WQ_W - Eigen::Vector3d(0, 0, cable_m);
      if (tick % 100 == 0) {
        VioSample vio;
        vio.time_s = t_s;
        vio.p_WB_W = truth_.p_WQ_W;
        vio_[vio_count_++ % kQueue] = vio;
        PayloadDetection d;
        d.time_s = t_s;
        d.found = true;
        d.p_CL_C = PayloadInCamera_C(params_, truth_);
        detections_[detection_count_++ % kQueue] = d;
      }
      // VIO delivered 20 ms after capture, detections 30 ms after
      while (vio_done_ < vio_count_ && vio_[vio_done_ % kQueue].time_s + 0.020 <= t_s + 1e-9) {
        estimator_->OnVio(vio_[vio_done_++ % kQueue]);
      }
      while (detection_done_ < detection_count_ &&
             detections_[detection_done_ % kQueue].time_s + 0.030 <= t_s + 1e-9) {
        estimator_->OnPayloadDetection(detections_[detection_done_++ % kQueue]);
      }
      if (tick % 6 == 0) {
        ImuSample imu;
        imu.time_s = t_s;
        imu.accel_B_mps2 = Eigen::Vector3d(0, 0, params_.gravity_mps2);
        estimator_->OnImu(imu);
        estimator_->OnAllocatedThrust(params_.HoverThrustN());
      }
      if (tick % 20 == 0) last_estimate_ = estimator_->Estimate(t_s);
    }
  }
  const SystemState& last_estimate() const { return last_estimate_; }

 private:
  static constexpr int kQueue = 8;  // messages in flight at once, at most
  Params params_;
  Estimator* estimator_;
  SystemState truth_;
  SystemState last_estimate_;
  VioSample vio_[kQueue];
  PayloadDetection detections_[kQueue];
  long vio_count_ = 0, vio_done_ = 0, detection_count_ = 0, detection_done_ = 0;
};

TEST(EstimatorAllocationTest, CountingAllocatorSeesAllocations) {
  EXPECT_GT(CountAllocations([]() { std::deque<double> d(100); }), 0);
}

// Each variant, hanging taut, then the payload lifted 0.2 m (slack for the hybrid estimator's
// mode detector): after a second in each phase, the next second allocates nothing.
TEST(EstimatorAllocationTest, SteadyStateAllocatesNothing) {
  const Params params = LoadParams(DefaultParamsPath());
  for (const std::string& name : EstimatorNames()) {
    SystemState initial;
    initial.p_WQ_W = Eigen::Vector3d(0, 0, 1.0);
    initial.p_WL_W = initial.p_WQ_W - Eigen::Vector3d(0, 0, params.cable_length_m);
    const auto estimator = MakeEstimator(name, EstimatorConfig{}, params, initial);
    HoverFeed feed(params, estimator.get());
    feed.Fly(0.0, 1.0, params.cable_length_m);
    EXPECT_EQ(CountAllocations([&]() { feed.Fly(1.0, 1.0, params.cable_length_m); }), 0)
        << name << ", taut";
    EXPECT_EQ(feed.last_estimate().mode, CableMode::kTaut) << name;
    feed.Fly(2.0, 1.0, params.cable_length_m - 0.2);
    EXPECT_EQ(CountAllocations([&]() { feed.Fly(3.0, 1.0, params.cable_length_m - 0.2); }), 0)
        << name << ", payload lifted";
    if (name == "hybrid") {
      EXPECT_EQ(feed.last_estimate().mode, CableMode::kSlack);
    }
  }
}

}  // namespace
}  // namespace hpa
