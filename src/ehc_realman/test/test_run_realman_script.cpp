// rostest: scripts/run_realman.sh (components arm + base) against a fake Water2 server on
// 127.0.0.1: the nodes come up with rosrun, /odom flows, the adapter listens; SIGINT to the
// script stops every node it started; --dry-run lists the rosrun commands.

#include "water2_fake_server.h"

#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <std_msgs/Float64.h>

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <functional>
#include <thread>

using ehc_realman_test::FakeWater2Server;

namespace {
const std::string kWorkspace = std::string(EHC_CONFIG_DIR) + "/..";
const std::string kScript = kWorkspace + "/src/ehc_realman/scripts/run_realman.sh";

bool waitFor(const std::function<bool()>& pred, double timeout) {
  return ehc_realman_test::waitFor(pred, timeout, 0.02);
}

std::string runCapture(const std::string& cmd, int& rc) {
  std::string out;
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return out;
  char buf[512];
  while (std::fgets(buf, sizeof(buf), p)) out += buf;
  rc = WEXITSTATUS(::pclose(p));
  return out;
}
}  // namespace

TEST(RunRealmanScript, DryRunListsTheRosrunCommands) {
  int rc = -1;
  const std::string out = runCapture("EHC_SKIP_SETUP=1 WATER2_HOST=10.0.0.7 bash " + kScript +
                                     " --dry-run base arm 2>&1", rc);
  EXPECT_EQ(rc, 0) << out;
  const auto arm = out.find("rosrun ehc_realman rm_arm_adapter _config:=config/realman/rm_arm_adapter.yaml");
  const auto base = out.find("rosrun ehc_realman water2_base_bridge _config:=config/realman/water2_base_bridge.yaml _host:=10.0.0.7");
  ASSERT_NE(arm, std::string::npos) << out;
  ASSERT_NE(base, std::string::npos) << out;
  EXPECT_LT(arm, base) << "fixed start order";
  runCapture("EHC_SKIP_SETUP=1 bash " + kScript + " --dry-run bogus 2>&1", rc);
  EXPECT_EQ(rc, 2);
}

TEST(RunRealmanScript, DryRunStartsTheControllerOnTheRealRobotTimerConfig) {
  int rc = -1;
  std::string out = runCapture("EHC_SKIP_SETUP=1 bash " + kScript + " --dry-run controller 2>&1", rc);
  EXPECT_NE(out.find("rosrun ehc_control ehc_controller_node _config:=config/realman/controller.yaml"
                     " _robot:=config/robots/realman_rm65_water2/robot.yaml"), std::string::npos) << out;
  EXPECT_EQ(out.find("must set node.trigger: timer"), std::string::npos) << out;
  // The simulator's lock-step configuration would never cycle on the robot: refused.
  out = runCapture("EHC_SKIP_SETUP=1 CONTROLLER_CONFIG=config/control/controller.yaml CONTROLLER_MODE=tsmm"
                   " bash " + kScript + " --dry-run controller 2>&1", rc);
  EXPECT_EQ(rc, 2) << out;
  EXPECT_NE(out.find("must set node.trigger: timer"), std::string::npos) << out;
  EXPECT_NE(out.find("_mode:=tsmm"), std::string::npos) << out;
}

TEST(RunRealmanScript, StartsTheRobotNodesAndStopsThemOnCtrlC) {
  ros::NodeHandle nh;
  FakeWater2Server server;
  server.start();
  server.setPose(0.5, -0.25, 0.1);
  std::atomic<int> odom{0};
  auto sub = nh.subscribe<nav_msgs::Odometry>(
      "/odom", 100, boost::function<void(const nav_msgs::Odometry::ConstPtr&)>(
                        [&](const nav_msgs::Odometry::ConstPtr&) { ++odom; }));
  ros::Publisher width = nh.advertise<std_msgs::Float64>("/arm/gripper/width", 1);

  const std::string log_dir = ::testing::TempDir() + "/run_realman_logs";
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::setenv("EHC_SKIP_SETUP", "1", 1);  // this environment already has the workspace set up
    ::setenv("WATER2_HOST", "127.0.0.1", 1);
    ::setenv("WATER2_PORT", std::to_string(server.port()).c_str(), 1);
    ::setenv("LOG_DIR", log_dir.c_str(), 1);
    ::execl("/bin/bash", "bash", kScript.c_str(), "arm", "base", static_cast<char*>(nullptr));
    std::_Exit(127);
  }
  ASSERT_GT(pid, 0);
  EXPECT_TRUE(waitFor([&] { return odom > 20; }, 30.0)) << "water2_base_bridge publishes /odom";
  EXPECT_TRUE(waitFor([&] { return width.getNumSubscribers() > 0; }, 30.0))
      << "rm_arm_adapter is up";
  EXPECT_GE(server.connections(), 1);

  ::kill(pid, SIGINT);  // Ctrl-C
  int status = 0;
  const bool exited = waitFor([&] { return ::waitpid(pid, &status, WNOHANG) == pid; }, 15.0);
  if (!exited) {
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &status, 0);
  }
  ASSERT_TRUE(exited) << "the script stops within 15 s";
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  // Its nodes are gone: no more /odom, nobody listens to the gripper topic.
  EXPECT_TRUE(waitFor([&] { return width.getNumSubscribers() == 0; }, 10.0));
  const int before = odom;
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  EXPECT_EQ(odom, before);
  server.stop();
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_run_realman_script");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  const int rc = RUN_ALL_TESTS();
  spinner.stop();
  return rc;
}
