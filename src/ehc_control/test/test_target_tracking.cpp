// Target tracking state: TfM counting (its restart on a new target, a moving target, paused
// windows, new intrinsics), and the supervisor's hold / TARGET_LOST / resume sequence. The
// camera model itself: test_pinhole_camera.

#include "ehc_common/config_node.h"
#include "ehc_control/controller_supervisor.h"
#include "ehc_control/target_tracker.h"
#include "ehc_test/control_fixtures.h"

#include <gtest/gtest.h>

using ehc_common::ConfigNode;


namespace ehc_control {
namespace {

using test::realmanCameraYaml;

Eigen::Isometry3d cameraLookingAlongX(double x) {  // optical z = world x, image x = -world y
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  T.translation() << x, 0, 0;
  return T;
}

TEST(TargetTracker, TfmIsTheFractionOfCyclesInViewSinceTheTargetWasSet) {
  TargetTracker t(loadPinholeCamera(realmanCameraYaml()), TargetTrackerParams{});
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

TEST(TargetTracker, MovingTargetsPausedWindowsAndNewIntrinsics) {
  TargetTracker t(loadPinholeCamera(realmanCameraYaml()), TargetTrackerParams{});
  const Eigen::Isometry3d looking = cameraLookingAlongX(0.0);
  // moveTarget starts a target like setTarget, then follows it whatever the jump.
  t.moveTarget(Eigen::Vector3d(2, 0, 0));
  EXPECT_TRUE(t.hasTarget());
  EXPECT_TRUE(t.observe(looking));
  t.moveTarget(Eigen::Vector3d(2, 1.5, 0));  // 1.5 m jump: out of view, the count continues
  EXPECT_FALSE(t.observe(looking));
  EXPECT_EQ(t.cycles(), 2);
  EXPECT_DOUBLE_EQ(t.tfm(), 0.5);
  EXPECT_TRUE(t.centre().isApprox(Eigen::Vector3d(2, 1.5, 0)));
  EXPECT_THROW(t.moveTarget(Eigen::Vector3d(std::nan(""), 0, 0)), std::invalid_argument);
  // Paused: in view is still answered, nothing is counted; resumed: counting goes on.
  t.moveTarget(Eigen::Vector3d(2, 0, 0));
  t.pause();
  EXPECT_TRUE(t.paused());
  EXPECT_TRUE(t.observe(looking));
  EXPECT_TRUE(t.inView());
  EXPECT_EQ(t.cycles(), 2);
  EXPECT_EQ(t.inViewCycles(), 1);
  t.resume();
  EXPECT_FALSE(t.paused());
  EXPECT_TRUE(t.observe(looking));
  EXPECT_EQ(t.cycles(), 3);
  EXPECT_NEAR(t.tfm(), 2.0 / 3.0, 1e-12);
  // New intrinsics: a narrower image loses the off-axis target; the count continues.
  t.moveTarget(Eigen::Vector3d(2, -0.5, 0));  // 0.5 m left of the axis at 2 m: u = 320 + 615 / 4
  EXPECT_TRUE(t.observe(looking));
  PinholeCamera narrow = t.camera();
  narrow.fx = narrow.fy = 200.0;
  narrow.width = 400;
  narrow.cx = 100.0;
  t.setCamera(narrow);
  EXPECT_EQ(t.camera().width, 400);
  EXPECT_TRUE(t.observe(looking));  // u = 100 + 200 / 4 = 150
  narrow.cx = 360.0;                // u = 410 >= 400
  t.setCamera(narrow);
  EXPECT_FALSE(t.observe(looking));
  EXPECT_EQ(t.cycles(), 6);
  EXPECT_EQ(t.inViewCycles(), 4);
  narrow.fx = -1.0;
  EXPECT_THROW(t.setCamera(narrow), std::invalid_argument);
  EXPECT_EQ(t.camera().fx, 200.0);
  // reset forgets the target and resumes counting.
  t.pause();
  t.reset();
  EXPECT_FALSE(t.hasTarget());
  EXPECT_FALSE(t.paused());
  EXPECT_EQ(t.cycles(), 0);
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
  p.require_obstacles = false;  // the target's rules alone
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
