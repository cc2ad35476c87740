// What the grasp sequencer node records (grasp_trace.h): trace.csv and the summary file in a
// temporary folder, and the trace's arm speed over the robot's arm joints: on the KUKA, whose
// joints are not named "joint...", it is the norm over its seven arm joints, not 0.

#include "ehc_bringup/grasp_trace.h"
#include "ehc_control/robot_config.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

namespace {

using ehc_bringup::GraspTraceRow;
using ehc_bringup::GraspTraceWriter;

struct TempDir {
  TempDir() {
    char tmpl[] = "/tmp/test_grasp_trace_XXXXXX";
    path = ::mkdtemp(tmpl);
  }
  ~TempDir() { std::system(("rm -rf '" + path + "'").c_str()); }
  std::string path;
};

std::string readFile(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

TEST(GraspTraceWriter, WritesTheHeaderAndOneLinePerCycle) {
  TempDir dir;
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
  EXPECT_EQ(readFile(file),
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
  TempDir dir;
  ehc_bringup::GraspResult r;
  r.name = "front";
  r.success = true;
  const std::string json = ehc_bringup::graspResultsToJson({r}, "ehc", 12.5);
  ASSERT_TRUE(ehc_bringup::writeGraspSummaryFile(dir.path + "/summary.json", json));
  EXPECT_EQ(readFile(dir.path + "/summary.json"), json + "\n");
  EXPECT_FALSE(ehc_bringup::writeGraspSummaryFile("/nonexistent_folder/summary.json", json));
}

TEST(JointStateArmSpeed, IsTheNormOverTheKukaArmJoints) {
  const ehc_control::RobotConfig kuka = ehc_control::loadRobotConfig(ehc_control::resolveRobotFile("kuka_iiwa14_kmr"));
  ASSERT_EQ(kuka.arm_joints.size(), 7u);
  for (const auto& j : kuka.arm_joints) EXPECT_NE(j.rfind("joint", 0), 0u) << j;  // what the prefix rule missed
  // A joint state in another order, with a finger joint the speed must leave out.
  std::vector<std::string> names{"finger_joint"};
  std::vector<double> rates{5.0};
  double squares = 0.0;
  for (std::size_t i = 0; i < kuka.arm_joints.size(); ++i) {
    const double v = 0.1 * static_cast<double>(i + 1) * (i % 2 ? -1.0 : 1.0);
    names.insert(names.begin(), kuka.arm_joints[i]);
    rates.insert(rates.begin(), v);
    squares += v * v;
  }
  const double speed = ehc_bringup::jointStateArmSpeed(kuka.arm_joints, names, rates);
  EXPECT_GT(speed, 0.0);
  EXPECT_NEAR(speed, std::sqrt(squares), 1e-12);
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
