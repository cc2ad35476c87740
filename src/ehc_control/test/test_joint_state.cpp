// armPositionsFromJointState: arm joints picked by name in any order (extra joints ignored);
// size mismatch, a missing arm joint and NaN/Inf are errors that leave the output unchanged.
// ControllerSupervisor::setJointState parses through it (and counts the rejections).

#include "ehc_control/controller_supervisor.h"
#include "ehc_control/joint_state.h"

#include <gtest/gtest.h>

#include <limits>

using namespace ehc_control;

namespace {
RobotConfig robot() {
  return loadRobotConfig(std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/robot.yaml");
}
}  // namespace

TEST(JointState, PicksTheArmJointsByNameInAnyOrder) {
  const RobotConfig rc = robot();
  ASSERT_EQ(rc.nArm(), 6);
  const std::vector<std::string> names = {"left_finger_joint", "joint6", "joint5", "joint4",
                                          "joint3", "joint2", "joint1"};
  const std::vector<double> positions = {0.03, 0.6, 0.5, 0.4, 0.3, 0.2, 0.1};
  Eigen::VectorXd q;
  ASSERT_EQ(armPositionsFromJointState(rc.arm_joints, names, positions, &q), "");
  ASSERT_EQ(q.size(), 6);
  for (int i = 0; i < 6; ++i) EXPECT_DOUBLE_EQ(q[i], 0.1 * (i + 1));
}

TEST(JointState, BadMessagesAreErrorsAndLeaveTheOutputUnchanged) {
  const RobotConfig rc = robot();
  const Eigen::VectorXd before = Eigen::VectorXd::Constant(6, 7.0);
  auto expectError = [&](const std::vector<std::string>& names, const std::vector<double>& positions,
                         const std::string& what) {
    Eigen::VectorXd q = before;
    const std::string why = armPositionsFromJointState(rc.arm_joints, names, positions, &q);
    EXPECT_NE(why.find(what), std::string::npos) << why;
    EXPECT_EQ(q, before);
  };
  expectError(rc.arm_joints, {0, 0, 0, 0, 0}, "6 names but 5 positions");
  expectError({"joint1", "joint2", "joint3", "joint4", "joint5", "gripper"}, {0, 0, 0, 0, 0, 0},
              "lacks arm joint 'joint6'");
  expectError(rc.arm_joints, {0, 0, std::numeric_limits<double>::quiet_NaN(), 0, 0, 0}, "NaN or Inf");
  expectError(rc.arm_joints, {0, 0, 0, std::numeric_limits<double>::infinity(), 0, 0}, "NaN or Inf");
  expectError({}, {}, "lacks arm joint 'joint1'");
}

TEST(JointState, SupervisorParsesThroughItAndCountsRejections) {
  const RobotConfig rc = robot();
  ControllerSupervisor s(rc, SupervisorParams());
  EXPECT_EQ(s.setJointState(1.0, rc.arm_joints, {0.1, 0.2, 0.3, 0.4, 0.5, 0.6}), "");
  EXPECT_DOUBLE_EQ(s.q()[5], 0.6);
  EXPECT_EQ(s.jointStateTime(), 1.0);
  EXPECT_EQ(s.setJointState(2.0, {"joint1"}, {0.0}), "joint state lacks arm joint 'joint2'");
  EXPECT_EQ(s.rejected(), 1);
  EXPECT_DOUBLE_EQ(s.q()[5], 0.6) << "state unchanged";
  EXPECT_EQ(s.jointStateTime(), 1.0);
}
