// SimWorld: Bullet robot bodies follow the integrated joint state; base motion; robot-world and
// self collisions reported; gripper grasp at the object centre succeeds after a 10 cm lift and
// one 10 cm off fails; a thin wall between the fingers is held; determinism per seed; bad
// inputs rejected.

#include "ehc_sim/sim_world.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>

using namespace ehc_sim;

namespace {
const std::string kConfig = std::string(EHC_CONFIG_DIR);

SimConfig simConfig(bool noise) {
  SimConfig c = loadSimConfig(EHC_SIM_CONFIG);
  c.fake_robot.noise.enabled = noise;
  return c;
}

ehc_control::RobotConfig robotConfig() {
  return ehc_control::loadRobotConfig(kConfig + "/robots/realman_rm65_water2/robot.yaml");
}

SceneConfig emptyScene() { return loadSceneConfigString("scene:\n  name: empty\n", "empty"); }

Eigen::VectorXd zeroCmd(const SimWorld& w) { return Eigen::VectorXd::Zero(w.robot().nDof()); }

/// Arm joint rates that move the TCP with linear velocity v (world frame), orientation held.
Eigen::VectorXd tcpVelocity(const SimWorld& w, const Eigen::Vector3d& v) {
  const auto& m = w.model();
  const ehc_control::Matrix6Xd J = m.jacobian(w.robot().basePose(), w.robot().armPositions(),
                                              m.config().tcp_frame);
  const Eigen::MatrixXd Ja = J.rightCols(m.nArm());
  Eigen::VectorXd twist = Eigen::VectorXd::Zero(6);
  twist.head<3>() = v;
  Eigen::VectorXd cmd = Eigen::VectorXd::Zero(m.nDof());
  cmd.tail(m.nArm()) = Ja.completeOrthogonalDecomposition().solve(twist);
  return cmd;
}

/// A scene with one 5 x `width` x 10 cm box held up by a pedestal so that its centre is at
/// `centre` with the box's y axis (`width`) along the gripper's closing axis.
SceneConfig graspScene(const Eigen::Vector3d& centre, double yaw, double width = 0.04) {
  char buf[1024];
  std::snprintf(buf, sizeof(buf), R"(
scene:
  name: grasp
  objects:
    - {name: box, shape: box, size: [0.05, %f, 0.10], position: [%f, %f, %f], rpy: [0, 0, %f], mass: 0.1}
  obstacles:
    - {name: pedestal, shape: box, size: [0.06, 0.06, %f], position: [%f, %f, %f], rpy: [0, 0, %f]}
)",
                width, centre.x(), centre.y(), centre.z(), yaw, centre.z() - 0.05, centre.x(), centre.y(),
                0.5 * (centre.z() - 0.05), yaw);
  return loadSceneConfigString(buf, "grasp_scene");
}

/// Forward grasp configuration: approach axis horizontal, TCP at (0.50, 0, 1.08) m.
Eigen::VectorXd forwardPose() {
  Eigen::VectorXd q(6);
  q << 0.0, 0.3, -1.9, 0.0, -M_PI / 2 + 1.6, 0.0;
  return q;
}
}  // namespace

// The collision model itself: ehc_control/test/test_robot_collision_model.
TEST(SimWorld, UsesTheUrdfCollisionModelAndPosesTheFingersFromTheGripper) {
  SimWorld w(simConfig(false), robotConfig(), emptyScene());
  const ehc_control::RobotCollisionModel& m = w.collisionModel();
  EXPECT_EQ(m.root(), "base_link");
  ASSERT_EQ(m.fingers().size(), 2u);
  EXPECT_GE(m.links().size(), 10u);
  auto fingerShift = [&](const std::string& finger) {  // from where WholeBodyModel puts it
    const Eigen::Isometry3d held = w.model().fk(w.robot().basePose(), w.robot().armPositions(), finger);
    return Eigen::Vector3d(w.linkPose(finger).translation() - held.translation());
  };
  const Eigen::Vector3d closing = w.linkPose("gripper_base_link").linear().col(1);
  EXPECT_NEAR(w.gripper().opening(), 0.035, 1e-12);  // starts open
  EXPECT_TRUE(fingerShift("left_finger_link").isApprox(0.035 * closing, 1e-9));
  EXPECT_TRUE(fingerShift("right_finger_link").isApprox(-0.035 * closing, 1e-9));
  EXPECT_TRUE(w.linkBodyPose("left_finger_link").translation().isApprox(w.linkPose("left_finger_link").translation(), 1e-6));
  w.commandGripper(true);  // closes on nothing
  for (int i = 0; i < 150; ++i) w.step(zeroCmd(w));
  ASSERT_NEAR(w.gripper().opening(), 0.0, 1e-12);
  EXPECT_LT(fingerShift("left_finger_link").norm(), 1e-9);
  EXPECT_LT(fingerShift("right_finger_link").norm(), 1e-9);
}

TEST(SimWorld, RobotBodiesFollowTheIntegratedState) {
  SimWorld w(simConfig(true), robotConfig(), emptyScene());
  Eigen::VectorXd cmd = zeroCmd(w);
  cmd << 0.3, 0.4, 0.5, -0.4, 0.3, 0.6, -0.5, 0.8;
  for (int i = 0; i < 50; ++i) w.step(cmd);
  for (const auto& l : w.collisionModel().links()) {
    const Eigen::Isometry3d fk = w.linkPose(l.name), body = w.linkBodyPose(l.name);
    EXPECT_LT((fk.translation() - body.translation()).norm(), 1e-5) << l.name;
    EXPECT_LT(Eigen::AngleAxisd(fk.linear().transpose() * body.linear()).angle(), 1e-5) << l.name;
  }
  EXPECT_NEAR(w.time(), 0.5, 1e-12);
  EXPECT_EQ(w.timeNs(), 500000000);
  // The camera frame is where WholeBodyModel puts it.
  EXPECT_TRUE(w.cameraPose().isApprox(
      w.model().fk(w.robot().basePose(), w.robot().armPositions(), "camera_color_optical_frame")));
}

TEST(SimWorld, TwistMovesTheBaseByTheExpectedDistance) {
  SimWorld w(simConfig(false), robotConfig(), emptyScene());
  Eigen::VectorXd cmd = zeroCmd(w);
  cmd[0] = 0.25;  // m/s for 2 s
  for (int i = 0; i < 200; ++i) w.step(cmd);
  EXPECT_NEAR(w.robot().basePose().x(), 0.5, 1e-9);
  EXPECT_NEAR(w.robot().basePose().y(), 0.0, 1e-12);
  EXPECT_NEAR(w.linkBodyPose("base_link").translation().x(), 0.5, 1e-5);
  EXPECT_FALSE(w.lastStep().robot_world_collision);
  EXPECT_EQ(w.counters().collision_steps, 0);
}

TEST(SimWorld, ReadyPoseIsCollisionFreeInTheShippedScenes) {
  for (const char* s : {"single_object.yaml", "table_three_objects.yaml"}) {
    SimWorld w(simConfig(false), robotConfig(), loadSceneConfig(kConfig + "/scenes/" + s));
    for (int i = 0; i < 20; ++i) {
      const StepReport& r = w.step(zeroCmd(w));
      ASSERT_FALSE(r.robot_world_collision) << s << ": " << (r.collisions.empty() ? "" : r.collisions[0].a + "|" + r.collisions[0].b);
      ASSERT_FALSE(r.self_collision) << s << ": " << (r.collisions.empty() ? "" : r.collisions[0].a + "|" + r.collisions[0].b);
    }
    // Objects rest on the table (settled, not falling through).
    for (std::size_t i = 0; i < w.scene().objects.size(); ++i)
      EXPECT_NEAR(w.objectPose(static_cast<int>(i)).translation().z(), w.scene().objects[i].position.z(), 2e-3)
          << s << " " << w.scene().objects[i].name;
  }
}

TEST(SimWorld, DrivingIntoAnObstacleIsReported) {
  const SceneConfig scene = loadSceneConfigString(
      "scene:\n  obstacles:\n    - {name: wall, size: [0.1, 2.0, 0.5], position: [0.8, 0, 0.25]}\n", "wall");
  SimWorld w(simConfig(false), robotConfig(), scene);
  Eigen::VectorXd cmd = zeroCmd(w);
  cmd[0] = 0.3;
  // Base radius 0.25 m: first contact when x > 0.8 - 0.05 - 0.25 = 0.5 m.
  int first = -1;
  for (int i = 0; i < 300 && first < 0; ++i)
    if (w.step(cmd).robot_world_collision) first = i;
  ASSERT_GE(first, 0) << "collision never reported";
  EXPECT_NEAR(w.robot().basePose().x(), 0.5, 0.01);
  bool base_hits_wall = false;
  for (const auto& c : w.lastStep().collisions)
    if (c.a == "base_link" && c.b == "wall") base_hits_wall = true;
  EXPECT_TRUE(base_hits_wall);
  EXPECT_GE(w.counters().collision_steps, 1);
}

TEST(SimWorld, SelfCollisionIsReported) {
  SimWorld w(simConfig(false), robotConfig(), emptyScene());
  // Ready pose: no self collision.
  EXPECT_FALSE(w.checkCollisions().self_collision);
  // Shoulder folded down and back: the upper arm / elbow goes into the base body.
  Eigen::VectorXd q = w.robot().armPositions();
  q << 0.0, -2.2, -2.3, 0.0, 0.0, 0.0;
  w.setRobotState(Eigen::Vector3d::Zero(), q);
  const StepReport r = w.checkCollisions();
  ASSERT_TRUE(r.self_collision);
  bool with_base = false;
  for (const auto& c : r.collisions) with_base |= c.self && (c.a == "base_link" || c.b == "base_link");
  EXPECT_TRUE(with_base);
}

TEST(SimWorld, GraspAtTheObjectCentreSucceedsAfterLift) {
  // Find where the TCP is in a downward pose, then put the object there.
  SimWorld probe(simConfig(false), robotConfig(), emptyScene());
  probe.setRobotState(Eigen::Vector3d::Zero(), forwardPose());
  const Eigen::Isometry3d tcp = probe.linkPose("ee_link");
  ASSERT_GT(tcp.linear().col(2).x(), 0.99) << "approach axis must point forward";
  const Eigen::Vector3d closing = tcp.linear().col(1);  // fingers close along the TCP y axis
  const double yaw = std::atan2(closing.y(), closing.x()) - M_PI / 2;  // box y along closing

  for (double offset : {0.0, 0.10}) {
    SCOPED_TRACE("offset " + std::to_string(offset));
    const Eigen::Vector3d centre = tcp.translation() + Eigen::Vector3d(offset, 0, 0);
    SimWorld w(simConfig(false), robotConfig(), graspScene(centre, yaw));
    w.setRobotState(Eigen::Vector3d::Zero(), forwardPose());
    for (int i = 0; i < 10; ++i) w.step(zeroCmd(w));  // settle
    const Eigen::Vector3d before = w.objectPose(0).translation();
    w.commandGripper(true);
    for (int i = 0; i < 150 && w.gripper().state() == GripperState::Closing; ++i) w.step(zeroCmd(w));
    if (offset == 0.0) {
      ASSERT_EQ(w.gripper().state(), GripperState::Holding);
      EXPECT_EQ(w.gripper().heldObject(), 0);
      // Stopped on the 4 cm box: the pads 2 x opening apart, within the contact tolerance.
      EXPECT_GE(w.gripper().opening(), 0.019);  // one cycle's travel into the box at most
      EXPECT_LE(w.gripper().opening(), 0.020 + simConfig(false).gripper.contact_tolerance);
    } else {
      ASSERT_EQ(w.gripper().state(), GripperState::ClosedEmpty);
      EXPECT_EQ(w.gripper().graspFailures(), 1);
    }
    // Lift 12 cm straight up.
    for (int i = 0; i < 120; ++i) {
      const StepReport& r = w.step(tcpVelocity(w, Eigen::Vector3d(0, 0, 0.1)));
      EXPECT_FALSE(r.robot_world_collision && offset == 0.0);
    }
    const Eigen::Vector3d after = w.objectPose(0).translation();
    if (offset == 0.0) {
      EXPECT_TRUE(w.gripper().graspSucceeded());
      EXPECT_EQ(w.gripper().graspSuccesses(), 1);
      EXPECT_GT(after.z() - before.z(), 0.10);
      // The object keeps its place relative to the gripper.
      EXPECT_NEAR((after - w.linkPose("ee_link").translation()).norm(),
                  (before - tcp.translation()).norm(), 0.01);
      // Release: the object falls back onto the pedestal.
      w.commandGripper(false);
      for (int i = 0; i < 150; ++i) w.step(zeroCmd(w));
      EXPECT_EQ(w.gripper().state(), GripperState::Open);
      EXPECT_LT(w.objectPose(0).translation().z(), after.z() - 0.05);
    } else {
      EXPECT_FALSE(w.gripper().graspSucceeded());
      EXPECT_EQ(w.gripper().graspSuccesses(), 0);
      EXPECT_LT((after - before).norm(), 0.005) << "the object stays where it was";
    }
  }
}

// A 5 mm wall (the thinnest box a scene takes; a mug's wall or handle, a bowl's rim) between the
// fingers, centred or off the TCP by its half thickness: the pads close until both touch it, and
// it is held (pads that stop short of each other close around such a wall on nothing).
TEST(SimWorld, TheFingersCloseOnAThinWall) {
  SimWorld probe(simConfig(false), robotConfig(), emptyScene());
  probe.setRobotState(Eigen::Vector3d::Zero(), forwardPose());
  const Eigen::Isometry3d tcp = probe.linkPose("ee_link");
  const Eigen::Vector3d closing = tcp.linear().col(1);
  const double yaw = std::atan2(closing.y(), closing.x()) - M_PI / 2;
  const double tolerance = simConfig(false).gripper.contact_tolerance, wall = 0.005;
  for (double shift : {0.0, 0.5 * wall, -0.5 * wall}) {
    SCOPED_TRACE("shift " + std::to_string(shift));
    SimWorld w(simConfig(false), robotConfig(), graspScene(tcp.translation() + shift * closing, yaw, wall));
    w.setRobotState(Eigen::Vector3d::Zero(), forwardPose());
    for (int i = 0; i < 10; ++i) w.step(zeroCmd(w));  // settle
    w.commandGripper(true);
    for (int i = 0; i < 150 && w.gripper().state() == GripperState::Closing; ++i) w.step(zeroCmd(w));
    ASSERT_EQ(w.gripper().state(), GripperState::Holding);
    EXPECT_EQ(w.gripper().heldObject(), 0);
    EXPECT_LE(w.gripper().opening(), std::abs(shift) + 0.5 * wall + tolerance + 1e-9);
  }
}

TEST(SimWorld, SameSeedSameTrajectoryDifferentSeedDifferent) {
  auto run = [](unsigned seed) {
    SimWorld w(simConfig(true), robotConfig(), loadSceneConfig(kConfig + "/scenes/table_three_objects.yaml"));
    w.reset(seed);
    std::vector<double> traj;
    Eigen::VectorXd cmd = zeroCmd(w);
    for (int i = 0; i < 300; ++i) {
      cmd[0] = 0.3 * std::sin(0.01 * i);
      cmd[1] = 0.2;
      cmd[3] = 0.3;
      w.step(cmd);
      for (int k = 0; k < 3; ++k) traj.push_back(w.robot().basePose()[k]);
      for (int k = 0; k < 6; ++k) traj.push_back(w.robot().armPositions()[k]);
      traj.push_back(w.objectPose(0).translation().z());
    }
    return traj;
  };
  const auto a = run(7), b = run(7), c = run(8);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << i;  // bit-identical
  double diff = 0;
  for (std::size_t i = 0; i < a.size(); ++i) diff = std::max(diff, std::abs(a[i] - c[i]));
  EXPECT_GT(diff, 1e-3);
}

TEST(SimWorld, ResetRestoresTheScene) {
  SimWorld w(simConfig(true), robotConfig(), loadSceneConfig(kConfig + "/scenes/single_object.yaml"));
  const Eigen::Isometry3d obj0 = w.objectPose(0);
  Eigen::VectorXd cmd = zeroCmd(w);
  cmd[0] = 0.4;
  for (int i = 0; i < 100; ++i) w.step(cmd);
  w.commandGripper(true);
  w.step(cmd);
  w.reset(3);
  EXPECT_EQ(w.stepCount(), 0);
  EXPECT_TRUE(w.robot().basePose().isZero());
  EXPECT_TRUE(w.robot().armPositions().isApprox(w.model().config().arm_ready));
  EXPECT_TRUE(w.objectPose(0).isApprox(obj0, 1e-6));
  EXPECT_EQ(w.gripper().state(), GripperState::Open);
  EXPECT_NEAR(w.gripper().opening(), 0.035, 1e-12);
}

TEST(SimWorld, BadCommandsThrow) {
  SimWorld w(simConfig(false), robotConfig(), emptyScene());
  EXPECT_THROW(w.step(Eigen::VectorXd::Zero(3)), std::invalid_argument);
  Eigen::VectorXd cmd = zeroCmd(w);
  cmd[4] = std::nan("");
  EXPECT_THROW(w.step(cmd), std::invalid_argument);
  EXPECT_EQ(w.stepCount(), 0);
  // A link robot.yaml names that the robot lacks: a start-up error naming the file and field.
  ehc_control::RobotConfig rc = robotConfig();
  rc.ignore_pairs.emplace_back("link1", "no_such_link");
  try {
    SimWorld bad(simConfig(false), rc, emptyScene());
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_link"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("robot.collision.ignore_pairs"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("robot.yaml"), std::string::npos);
  }
  rc = robotConfig();
  rc.floor_links = {"wheel_link"};
  EXPECT_THROW(SimWorld(simConfig(false), rc, emptyScene()), std::invalid_argument);
}

TEST(ParallelGripper, StateMachine) {
  GripperConfig c;
  ParallelGripper g(c, 0.035);
  EXPECT_EQ(g.state(), GripperState::Open);
  g.command(true);
  EXPECT_EQ(g.state(), GripperState::Closing);
  g.advance(0.1);
  EXPECT_NEAR(g.opening(), 0.030, 1e-12);
  EXPECT_FALSE(g.onFingerContacts({2}, {}));  // one finger only: no grasp
  EXPECT_TRUE(g.onFingerContacts({2, 5}, {5}));
  EXPECT_EQ(g.state(), GripperState::Holding);
  EXPECT_EQ(g.heldObject(), 5);
  g.advance(0.1);
  EXPECT_NEAR(g.opening(), 0.030, 1e-12) << "fingers stop on the object";
  g.onHeldObjectHeight(0.80);
  g.onHeldObjectHeight(0.89);
  EXPECT_FALSE(g.graspSucceeded());
  g.onHeldObjectHeight(0.90);
  EXPECT_TRUE(g.graspSucceeded());
  g.command(false);
  EXPECT_EQ(g.heldObject(), -1);
  for (int i = 0; i < 10; ++i) g.advance(0.1);
  EXPECT_EQ(g.state(), GripperState::Open);
  g.command(true);
  for (int i = 0; i < 10; ++i) g.advance(0.1);
  EXPECT_EQ(g.state(), GripperState::ClosedEmpty);
  EXPECT_EQ(g.graspFailures(), 1);
  EXPECT_THROW(ParallelGripper(c, -1.0), std::invalid_argument);
}
