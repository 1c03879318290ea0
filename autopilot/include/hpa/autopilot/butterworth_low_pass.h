#pragma once
// Second-order Butterworth low-pass filter per axis, discretised by the bilinear transform with
// frequency pre-warping (the form of PX4's math::LowPassFilter2p, which filters the gyro and its
// derivative for the rate loop).

#include <Eigen/Core>

namespace hpa {

/// Second-order Butterworth low-pass on a 3-vector at a fixed sample rate.
class ButterworthLowPass {
 public:
  /// cutoff_hz <= 0 or >= sample_hz / 2 gives a pass-through filter (PX4: 0 disables it).
  ButterworthLowPass(double sample_hz, double cutoff_hz);

  /// Filters one sample; the first sample after construction or Reset() sets the steady state.
  Eigen::Vector3d Apply(const Eigen::Vector3d& sample);
  /// Sets the filter's state to the steady state of a constant input `sample`.
  void Reset(const Eigen::Vector3d& sample);
  /// Forgets the state: the next Apply() starts from its own sample.
  void Clear() { initialised_ = false; }
  /// True when the filter passes samples through unchanged.
  bool pass_through() const { return pass_through_; }

 private:
  bool pass_through_ = true;
  bool initialised_ = false;
  double b0_ = 1.0, b1_ = 0.0, b2_ = 0.0;             // numerator
  double a1_ = 0.0, a2_ = 0.0;                        // denominator (a0 = 1)
  Eigen::Vector3d delay1_ = Eigen::Vector3d::Zero();  // direct form II state w[n-1]  (3)
  Eigen::Vector3d delay2_ = Eigen::Vector3d::Zero();  // direct form II state w[n-2]  (3)
};

}  // namespace hpa
