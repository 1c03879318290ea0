#pragma once
// Sensor messages shared by the simulated sensors (sim/) and the flight code (estimator/).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

namespace hpa {

/// One IMU sample (500 Hz): gyro and specific force in the body frame, with noise and bias.
struct ImuSample {
  double time_s = 0.0;
  Eigen::Vector3d gyro_B_radps = Eigen::Vector3d::Zero();  // body rate + bias + noise  (3)
  Eigen::Vector3d accel_B_mps2 = Eigen::Vector3d::Zero();  // specific force R^T (a + g e3)  (3)
};

/// One gyro sample for the body-rate loop (its own output data rate): body rate with noise and
/// bias, stamped with the start of the interval it averages.
struct GyroSample {
  double time_s = 0.0;
  Eigen::Vector3d gyro_B_radps = Eigen::Vector3d::Zero();  // body rate + bias + noise  (3)
};

/// The gripper's switch: whether it holds the payload (the flight stack's gripper flag).
struct GripperSample {
  double time_s = 0.0;
  bool active = false;  // holding the payload
};

/// One VIO pose (30 Hz), stamped with the time it was measured (it arrives later).
struct VioSample {
  double time_s = 0.0;                                       // capture time
  Eigen::Vector3d p_WB_W = Eigen::Vector3d::Zero();          // body position, world  (3)
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();  // body attitude
  Eigen::Vector3d v_WB_W = Eigen::Vector3d::Zero();          // body velocity, world  (3)
};

/// What the payload detector (or the analytic camera) reports for one camera frame.
struct PayloadDetection {
  double time_s = 0.0;                                  // capture time of the frame
  bool found = false;                                   // false: no usable payload in view
  std::string reason;                                   // why not found (empty if found)
  Eigen::Vector3d p_CL_C = Eigen::Vector3d::Zero();     // payload centre in camera frame  (3)
  Eigen::Vector2d centre_px = Eigen::Vector2d::Zero();  // ellipse centre, pixels  (2)
  double radius_px = 0.0;                               // ellipse minor semi-axis, pixels
};

}  // namespace hpa
