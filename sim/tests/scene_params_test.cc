// models/scene.xml agrees with models/params.yaml (docs/design.md section 2: the controller's model
// and the simulated world must never silently disagree). Loads the raw MJCF, not through World,
// which would overwrite masses and the cable length from params.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "hpa/models/params.h"
#include "hpa/models/rotor_model.h"

namespace hpa::sim {
namespace {

// MJCF numbers are written with 6 significant digits (e.g. 0.106066, 5.02335): relative 1e-5.
constexpr double kXmlRelTol = 1e-5;

class SceneParamsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    params_ = LoadParams(DefaultParamsPath());
    char error[1024] = "";
    const std::string path = std::string(HPA_SOURCE_DIR) + "/models/scene.xml";
    m_ = mj_loadXML(path.c_str(), nullptr, error, sizeof(error));
    ASSERT_NE(m_, nullptr) << error;
    EXPECT_STREQ(error, "") << "load warning";
  }
  void TearDown() override {
    if (m_ != nullptr) mj_deleteModel(m_);
  }
  int Id(mjtObj type, const char* name) {
    const int id = mj_name2id(m_, type, name);
    EXPECT_GE(id, 0) << name;
    return id;
  }
  static void ExpectRel(double actual, double expected, const std::string& what) {
    EXPECT_NEAR(actual, expected, kXmlRelTol * std::max(1e-3, std::abs(expected))) << what;
  }

  Params params_;
  mjModel* m_ = nullptr;
};

TEST_F(SceneParamsTest, TimestepGravityAndOffscreenSize) {
  EXPECT_DOUBLE_EQ(m_->opt.timestep, 0.001);
  EXPECT_DOUBLE_EQ(m_->opt.gravity[2], -params_.gravity_mps2);
  EXPECT_EQ(m_->vis.global.offwidth, params_.camera_width_px);
  EXPECT_EQ(m_->vis.global.offheight, params_.camera_height_px);
}

TEST_F(SceneParamsTest, MassesAndInertia) {
  const int quad = Id(mjOBJ_BODY, "quadrotor");
  const int payload = Id(mjOBJ_BODY, "payload");
  ExpectRel(m_->body_mass[quad], params_.quad_mass_kg, "quad mass");
  for (int i = 0; i < 3; ++i) {
    ExpectRel(m_->body_inertia[3 * quad + i], params_.inertia_B_kgm2(i), "quad inertia");
    EXPECT_NEAR(m_->body_ipos[3 * quad + i], 0.0, 1e-12) << "body origin = centre of mass";
  }
  ExpectRel(m_->body_mass[payload], params_.payload_mass_kg, "payload mass");
  // solid sphere: 2/5 m r^2
  const double sphere_inertia =
      0.4 * params_.payload_mass_kg * params_.payload_radius_m * params_.payload_radius_m;
  for (int i = 0; i < 3; ++i) {
    ExpectRel(m_->body_inertia[3 * payload + i], sphere_inertia, "payload inertia");
  }
  const int sphere = Id(mjOBJ_GEOM, "payload_sphere");
  EXPECT_EQ(m_->geom_type[sphere], mjGEOM_SPHERE);
  ExpectRel(m_->geom_size[3 * sphere], params_.payload_radius_m, "payload radius");
  const int box = Id(mjOBJ_GEOM, "quadrotor_box");
  EXPECT_EQ(m_->geom_type[box], mjGEOM_BOX);
  for (int i = 0; i < 3; ++i) {
    ExpectRel(m_->geom_size[3 * box + i], params_.body_half_size_m(i), "body half size");
  }
}

TEST_F(SceneParamsTest, CableIsALimitedTendonBetweenTheCentres) {
  const int cable = Id(mjOBJ_TENDON, "cable");
  EXPECT_TRUE(m_->tendon_limited[cable]);
  EXPECT_DOUBLE_EQ(m_->tendon_range[2 * cable], 0.0);
  ExpectRel(m_->tendon_range[2 * cable + 1], params_.cable_length_m, "cable length");
  ASSERT_EQ(m_->tendon_num[cable], 2);
  const int adr = m_->tendon_adr[cable];
  const int s0 = m_->wrap_objid[adr], s1 = m_->wrap_objid[adr + 1];
  EXPECT_EQ(m_->site_bodyid[s0], Id(mjOBJ_BODY, "quadrotor"));
  EXPECT_EQ(m_->site_bodyid[s1], Id(mjOBJ_BODY, "payload"));
  for (int i = 0; i < 3; ++i) {
    EXPECT_DOUBLE_EQ(m_->site_pos[3 * s0 + i], 0.0);
    EXPECT_DOUBLE_EQ(m_->site_pos[3 * s1 + i], 0.0);
  }
  // qpos0 hangs the payload exactly one cable length below the quadrotor
  const int quad = Id(mjOBJ_BODY, "quadrotor"), payload = Id(mjOBJ_BODY, "payload");
  ExpectRel(m_->body_pos[3 * quad + 2] - m_->body_pos[3 * payload + 2], params_.cable_length_m,
            "hanging at qpos0");
}

TEST_F(SceneParamsTest, RotorSitesGearsAndThrustRange) {
  const double torque_per_thrust_m = params_.k_m_Nm_per_radps2 / params_.k_f_N_per_radps2;
  const double w_min = params_.motor_speed_min_radps, w_max = params_.motor_speed_max_radps;
  for (int i = 0; i < 4; ++i) {
    const std::string name = "rotor" + std::to_string(i);
    const int act = Id(mjOBJ_ACTUATOR, name.c_str());
    const int site = Id(mjOBJ_SITE, name.c_str());
    ASSERT_GE(act, 0);
    EXPECT_EQ(m_->actuator_trntype[act], mjTRN_SITE);
    EXPECT_EQ(m_->actuator_trnid[2 * act], site);
    EXPECT_EQ(m_->site_bodyid[site], Id(mjOBJ_BODY, "quadrotor"));
    const Eigen::Vector3d r = RotorPosition_B(params_, i);
    for (int k = 0; k < 3; ++k) ExpectRel(m_->site_pos[3 * site + k], r(k), name + " position");
    // site frame = body frame, so gear (0 0 1) is body z and gear[5] the yaw reaction torque
    EXPECT_DOUBLE_EQ(m_->site_quat[4 * site], 1.0);
    const double expected_gear[6] = {0, 0, 1, 0, 0, RotorSpin(i) * torque_per_thrust_m};
    for (int k = 0; k < 6; ++k) ExpectRel(m_->actuator_gear[6 * act + k], expected_gear[k], name);
    EXPECT_TRUE(m_->actuator_ctrllimited[act]);
    ExpectRel(m_->actuator_ctrlrange[2 * act], params_.k_f_N_per_radps2 * w_min * w_min,
              name + " min thrust");
    ExpectRel(m_->actuator_ctrlrange[2 * act + 1], params_.k_f_N_per_radps2 * w_max * w_max,
              name + " max thrust");
  }
}

TEST_F(SceneParamsTest, PayloadCameraMatchesTheCameraModel) {
  const int cam = Id(mjOBJ_CAMERA, "payload_camera");
  EXPECT_EQ(m_->cam_bodyid[cam], Id(mjOBJ_BODY, "quadrotor"));
  ExpectRel(m_->cam_fovy[cam], params_.camera_fovy_deg, "fovy");
  for (int i = 0; i < 3; ++i) ExpectRel(m_->cam_pos[3 * cam + i], params_.t_BC_B_m(i), "t_BC_B");
  // MuJoCo camera axes (x right, y up, looking along -z) -> OpenCV's C (x right, y down, z fwd)
  const Eigen::Quaterniond q_B_cam(m_->cam_quat[4 * cam], m_->cam_quat[4 * cam + 1],
                                   m_->cam_quat[4 * cam + 2], m_->cam_quat[4 * cam + 3]);
  const Eigen::Matrix3d R_BC =
      q_B_cam.toRotationMatrix() * Eigen::Vector3d(1, -1, -1).asDiagonal().toDenseMatrix();
  EXPECT_TRUE(R_BC.isApprox(params_.R_BC, 1e-12)) << R_BC;
  EXPECT_GE(Id(mjOBJ_CAMERA, "chase"), 0);
}

TEST_F(SceneParamsTest, PayloadNeverCollidesWithTheQuadrotorButBothHitTheGround) {
  auto collide = [this](int g1, int g2) {
    return (m_->geom_contype[g1] & m_->geom_conaffinity[g2]) ||
           (m_->geom_contype[g2] & m_->geom_conaffinity[g1]);
  };
  const int ground = Id(mjOBJ_GEOM, "ground");
  const int box = Id(mjOBJ_GEOM, "quadrotor_box");
  const int sphere = Id(mjOBJ_GEOM, "payload_sphere");
  EXPECT_FALSE(collide(box, sphere));
  EXPECT_TRUE(collide(box, ground));
  EXPECT_TRUE(collide(sphere, ground));
  // every other quadrotor geom is visual only
  const int quad = Id(mjOBJ_BODY, "quadrotor");
  for (int g = 0; g < m_->ngeom; ++g) {
    if (m_->geom_bodyid[g] != quad || g == box) continue;
    EXPECT_FALSE(collide(g, ground) || collide(g, sphere)) << mj_id2name(m_, mjOBJ_GEOM, g);
  }
}

TEST_F(SceneParamsTest, GripperIsAnInactiveMocapWeldOnThePayload) {
  const int gripper = Id(mjOBJ_BODY, "gripper");
  EXPECT_GE(m_->body_mocapid[gripper], 0);
  const int weld = Id(mjOBJ_EQUALITY, "gripper_weld");
  EXPECT_EQ(m_->eq_type[weld], mjEQ_WELD);
  EXPECT_FALSE(m_->eq_active[weld]);
  EXPECT_EQ(m_->eq_obj1id[weld], gripper);
  EXPECT_EQ(m_->eq_obj2id[weld], Id(mjOBJ_BODY, "payload"));
}

}  // namespace
}  // namespace hpa::sim
