// What the grasp sequencer node records (grasp_trace.h): trace.csv and the summary file in a
// temporary folder, and the trace's arm speed over the robot's arm joints: on every shipped
// robot (the KUKA's, the Kinova's and the UR5e's joints are not named "joint...") it is the norm
// over robot.yaml's arm joints, not 0.

#include "ehc_bringup/grasp_trace.h"
#include "ehc_control/robot_config.h"
#include "ehc_test/temp_dir.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

namespace {

using ehc_bringup::GraspTraceRow;
using ehc_bringup::GraspTraceWriter;

using ehc_test::readText;
using ehc_test::TempDir;

TEST(GraspTraceWriter, WritesTheHeaderAndOneLinePerCycle) {
  TempDir dir("test_grasp_trace");
  const std::string file = dir.path + "/trace.csv";
  {
    GraspTraceWriter w(file);
    GraspTraceRow r;
    r.t = 1.23456;
    r.object = "front";
    r.phase = ehc_bringup::GraspPhase::Approach;
    r.controller_phase = "TRACKING";
    r.error_norm = 0.5;
    r.position_error = 0.25;
    r.sig_omega = 0.125;
    r.base_speed = 0.2;
    r.base_turn = 0.1;
    r.arm_speed = 0.3;
    r.target_in_fov = true;
    r.obstacle_rows = 4;
    r.qp_status = "OK";
    w.write(r);
    r.t = 2.0;
    r.phase = ehc_bringup::GraspPhase::Done;
    r.target_in_fov = false;
    r.sig_omega = std::nan("");
    w.write(r);
    w.flush();
  }
  EXPECT_EQ(readText(file),
            "t,object,phase,controller_phase,error_norm,position_error,sig_omega,base_speed,base_turn_rate,arm_speed,"
            "target_in_fov,obstacle_rows,qp_status\n"
            "1.235,front,APPROACH,TRACKING,0.50000,0.25000,0.12500,0.20000,0.10000,0.30000,1,4,OK\n"
            "2.000,front,DONE,TRACKING,0.50000,0.25000,nan,0.20000,0.10000,0.30000,0,4,OK\n");
}

TEST(GraspTraceWriter, AFileThatCannotBeWrittenIsAnError) {
  try {
    GraspTraceWriter w("/nonexistent_folder/trace.csv");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "[GraspTraceWriter] cannot write the trace file /nonexistent_folder/trace.csv");
  }
}

TEST(GraspSummaryFile, WritesTheJsonAndANewline) {
  TempDir dir("test_grasp_trace");
  ehc_bringup::GraspResult r;
  r.name = "front";
  r.success = true;
  const std::string json = ehc_bringup::graspResultsToJson({r}, "ehc", 12.5);
  ASSERT_TRUE(ehc_bringup::writeGraspSummaryFile(dir.path + "/summary.json", json));
  EXPECT_EQ(readText(dir.path + "/summary.json"), json + "\n");
  EXPECT_FALSE(ehc_bringup::writeGraspSummaryFile("/nonexistent_folder/summary.json", json));
}

class JointStateArmSpeedOfEveryRobot : public ::testing::TestWithParam<std::string> {};

TEST_P(JointStateArmSpeedOfEveryRobot, IsTheNormOverItsArmJointsInAnyOrder) {
  const ehc_control::RobotConfig rc = ehc_control::loadRobotConfig(ehc_control::resolveRobotFile(GetParam()));
  // A joint state in another order, with a finger joint the speed must leave out.
  std::vector<std::string> names{"finger_joint"};
  std::vector<double> rates{5.0};
  double squares = 0.0;
  for (std::size_t i = 0; i < rc.arm_joints.size(); ++i) {
    const double v = 0.1 * static_cast<double>(i + 1) * (i % 2 ? -1.0 : 1.0);
    names.insert(names.begin(), rc.arm_joints[i]);
    rates.insert(rates.begin(), v);
    squares += v * v;
  }
  const double speed = ehc_bringup::jointStateArmSpeed(rc.arm_joints, names, rates);
  EXPECT_GT(speed, 0.0);
  EXPECT_NEAR(speed, std::sqrt(squares), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Robots, JointStateArmSpeedOfEveryRobot, ::testing::ValuesIn(ehc_control::robotNames()),
                         [](const auto& info) { return info.param; });

// What the joint-name prefix rule missed: the arm joints of the KUKA, the Kinova and the UR5e
// are not named "joint...".
TEST(JointStateArmSpeed, ShippedRobotsWhoseJointsAreNotNamedJoint) {
  int others = 0;
  for (const std::string& robot : ehc_control::robotNames()) {
    const auto rc = ehc_control::loadRobotConfig(ehc_control::resolveRobotFile(robot));
    others += std::none_of(rc.arm_joints.begin(), rc.arm_joints.end(), [](const std::string& j) { return j.rfind("joint", 0) == 0; });
  }
  EXPECT_GE(others, 3);
}

TEST(JointStateArmSpeed, IsTheNormOverTheRealmanArmJointsAsBefore) {
  const ehc_control::RobotConfig rm = ehc_control::loadRobotConfig(ehc_control::resolveRobotFile("realman_rm65_water2"));
  const std::vector<double> rates{0.1, -0.2, 0.3, 0.0, 0.05, -0.4};
  ASSERT_EQ(rm.arm_joints.size(), rates.size());
  double squares = 0.0;
  for (double v : rates) squares += v * v;
  EXPECT_EQ(ehc_bringup::jointStateArmSpeed(rm.arm_joints, rm.arm_joints, rates), std::sqrt(squares));  // same bits
}

TEST(JointStateArmSpeed, IsNaNWithoutEveryArmJointsRate) {
  const std::vector<std::string> arm{"a1", "a2"};
  EXPECT_TRUE(std::isnan(ehc_bringup::jointStateArmSpeed(arm, {"a1"}, {0.1})));               // a joint missing
  EXPECT_TRUE(std::isnan(ehc_bringup::jointStateArmSpeed(arm, {"a1", "a2"}, {})));            // no rates
  EXPECT_TRUE(std::isnan(ehc_bringup::jointStateArmSpeed(arm, {"a1", "a2"}, {0.1, std::nan("")})));
  EXPECT_DOUBLE_EQ(ehc_bringup::jointStateArmSpeed(arm, {"a2", "a1"}, {0.3, 0.4}), 0.5);
}

}  // namespace
