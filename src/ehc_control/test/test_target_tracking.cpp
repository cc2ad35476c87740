// Target tracking state: camera intrinsics from camera.yaml, in-view test, TfM counting (and
// its restart on a new target), and the supervisor's hold / TARGET_LOST / resume sequence.

#include "ehc_control/config_node.h"
#include "ehc_control/controller_supervisor.h"
#include "ehc_control/target_tracker.h"
#include "test_helpers.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

namespace ehc_control {
namespace {

std::string cameraYaml() { return std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/camera.yaml"; }

std::string writeTemp(const std::string& name, const std::string& text) {
  const std::string path = "/tmp/ehc_control_test_" + std::to_string(::getpid()) + "_" + name;
  std::ofstream(path) << text;
  return path;
}

TEST(PinholeCamera, LoadsTheD435Intrinsics) {
  const PinholeCamera c = loadPinholeCamera(cameraYaml());
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.height, 480);
  EXPECT_EQ(c.fx, 615.0);
  EXPECT_EQ(c.fy, 615.0);
  EXPECT_EQ(c.cx, 320.0);
  EXPECT_EQ(c.cy, 240.0);
}

TEST(PinholeCamera, BadFilesNameTheFileAndField) {
  try {
    loadPinholeCamera("/nonexistent/camera.yaml");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("[PinholeCamera]"), std::string::npos) << e.what();
  }
  const std::string no_k = writeTemp("no_k.yaml", "image_width: 640\nimage_height: 480\n");
  try {
    loadPinholeCamera(no_k);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("camera_matrix"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(no_k), std::string::npos) << e.what();
  }
  const std::string bad_f =
      writeTemp("bad_f.yaml", "image_width: 640\nimage_height: 480\ncamera_matrix: {data: [0, 0, 320, 0, 615, 240, 0, 0, 1]}\n");
  try {
    loadPinholeCamera(bad_f);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("fx"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(bad_f), std::string::npos) << e.what();
  }
  std::remove(no_k.c_str());
  std::remove(bad_f.c_str());
}

TEST(PinholeCamera, InViewMeansInsideTheImageAtPositiveDepth) {
  const PinholeCamera c = loadPinholeCamera(cameraYaml());
  Eigen::Vector2d uv;
  EXPECT_TRUE(c.projectsInside(Eigen::Vector3d(0, 0, 1), &uv));
  EXPECT_TRUE(uv.isApprox(Eigen::Vector2d(320, 240)));
  EXPECT_FALSE(c.projectsInside(Eigen::Vector3d(0, 0, -1)));  // behind
  EXPECT_FALSE(c.projectsInside(Eigen::Vector3d(0, 0, 0)));
  // Horizontal edge: u = 320 + 615 x / z; inside for u < 640, i.e. x/z < 320/615.
  EXPECT_TRUE(c.projectsInside(Eigen::Vector3d(0.52, 0, 1)));
  EXPECT_FALSE(c.projectsInside(Eigen::Vector3d(0.521, 0, 1)));
  EXPECT_TRUE(c.projectsInside(Eigen::Vector3d(-0.52, 0, 1)));
  EXPECT_FALSE(c.projectsInside(Eigen::Vector3d(-0.521, 0, 1)));
  // Vertical edge: v = 240 + 615 y / z; inside for |y/z| < 240/615 = 0.390.
  EXPECT_TRUE(c.projectsInside(Eigen::Vector3d(0, 0.39, 1)));
  EXPECT_FALSE(c.projectsInside(Eigen::Vector3d(0, 0.391, 1)));
  EXPECT_FALSE(c.projectsInside(Eigen::Vector3d(std::nan(""), 0, 1)));
}

Eigen::Isometry3d cameraLookingAlongX(double x) {  // optical z = world x, image x = -world y
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  T.translation() << x, 0, 0;
  return T;
}

TEST(TargetTracker, TfmIsTheFractionOfCyclesInViewSinceTheTargetWasSet) {
  TargetTracker t(loadPinholeCamera(cameraYaml()), TargetTrackerParams{});
  EXPECT_FALSE(t.observe(cameraLookingAlongX(0.0)));  // no target: not counted
  EXPECT_EQ(t.cycles(), 0);
  EXPECT_TRUE(t.setTarget(Eigen::Vector3d(2, 0, 0)));
  const Eigen::Isometry3d looking = cameraLookingAlongX(0.0);
  Eigen::Isometry3d away = looking;
  away.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix() * looking.linear();
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(t.observe(looking));
  EXPECT_FALSE(t.observe(away));
  EXPECT_FALSE(t.inView());
  EXPECT_DOUBLE_EQ(t.tfm(), 0.75);
  EXPECT_FALSE(t.observe(cameraLookingAlongX(3.0)));  // target behind the camera
  EXPECT_DOUBLE_EQ(t.tfm(), 0.6);
  // Perception noise on the same target: the count continues.
  EXPECT_FALSE(t.setTarget(Eigen::Vector3d(2.02, 0.01, 0)));
  EXPECT_TRUE(t.observe(looking));
  EXPECT_EQ(t.cycles(), 6);
  EXPECT_NEAR(t.tfm(), 4.0 / 6.0, 1e-12);
  // A different target restarts TfM.
  EXPECT_TRUE(t.setTarget(Eigen::Vector3d(2.5, 0.5, 0)));
  EXPECT_EQ(t.cycles(), 0);
  EXPECT_DOUBLE_EQ(t.tfm(), 0.0);
  EXPECT_FALSE(t.observe(away));
  EXPECT_DOUBLE_EQ(t.tfm(), 0.0);
  t.reset();
  EXPECT_FALSE(t.hasTarget());
  EXPECT_THROW(t.setTarget(Eigen::Vector3d(std::nan(""), 0, 0)), std::invalid_argument);
}

TEST(TargetTracker, ParamsLoadAndResolveTheCameraPath) {
  const ConfigNode n = ConfigNode::loadString("camera: ../robots/x/camera.yaml\nnew_target_distance: 0.2\n",
                                              "/a/b/controller.yaml", "ControllerNode");
  const TargetTrackerParams p = loadTargetTrackerParams(n);
  EXPECT_EQ(p.camera_file, "/a/b/../robots/x/camera.yaml");
  EXPECT_EQ(p.new_target_distance, 0.2);
  EXPECT_THROW(loadTargetTrackerParams(ConfigNode::loadString("new_target_distance: -1\n", "c.yaml", "X")),
               std::invalid_argument);
}

TEST(ControllerSupervisor, HoldsTheLastTargetThenStopsThenResumes) {
  const RobotConfig rc = test::realmanConfig();
  SupervisorParams p;
  p.target_timeout = 0.5;
  ControllerSupervisor s(rc, p);
  auto feed = [&](double t) {
    ASSERT_EQ(s.setJointState(t, rc.arm_joints, std::vector<double>(rc.arm_ready.data(), rc.arm_ready.data() + rc.nArm())), "");
    ASSERT_EQ(s.setBasePose(t, Eigen::Vector3d::Zero()), "");
  };
  EXPECT_LT(s.targetAge(0.0), 0.0);
  Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
  target.translation() << 1.0, 0.0, 0.8;
  feed(1.0);
  EXPECT_EQ(s.check(1.0).phase, ControlPhase::Idle);
  ASSERT_EQ(s.setTarget(1.0, target), "");
  // No new target pose (out of view / not detected): keeps serving the last good one.
  for (double t = 1.0; t <= 1.5; t += 0.1) {
    feed(t);
    EXPECT_TRUE(s.check(t).run) << t;
    EXPECT_NEAR(s.targetAge(t), t - 1.0, 1e-12);
    EXPECT_TRUE(s.target().isApprox(target));
  }
  // A bad pose does not replace the good one nor refresh it.
  Eigen::Isometry3d bad = target;
  bad.translation().x() = std::nan("");
  EXPECT_NE(s.setTarget(1.55, bad), "");
  EXPECT_TRUE(s.target().isApprox(target));
  // Lost longer than the timeout: stop.
  feed(1.6);
  const SupervisorDecision lost = s.check(1.6);
  EXPECT_FALSE(lost.run);
  EXPECT_EQ(lost.phase, ControlPhase::TargetLost);
  EXPECT_NEAR(s.targetAge(1.6), 0.6, 1e-12);
  // Re-acquired: continue.
  target.translation().x() = 1.01;
  ASSERT_EQ(s.setTarget(1.7, target), "");
  feed(1.7);
  EXPECT_TRUE(s.check(1.7).run);
  EXPECT_NEAR(s.targetAge(1.7), 0.0, 1e-12);
  EXPECT_NEAR(s.target().translation().x(), 1.01, 1e-12);
}

}  // namespace
}  // namespace ehc_control
