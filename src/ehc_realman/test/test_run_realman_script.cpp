// rostest: scripts/run_realman.sh (components arm + base) against a fake Water2 server on
// 127.0.0.1: the nodes come up with rosrun, /odom flows, the adapter listens; SIGINT to the
// script stops every node it started; --dry-run lists the rosrun commands.
// Private parameters of an earlier run (e.g. _mode:=tsmm) are deleted before a node
// starts; robot_state_publisher (started with the arm) publishes base_link -> ... -> camera tf
// from /joint_states, matching the controller's kinematic model (URDF + robot.yaml).

#include "water2_fake_server.h"

#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <std_msgs/Float64.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "ehc_control/whole_body_model.h"

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

TEST(RunRealmanScript, DryRunStartsTheControllerOnItsTimer) {
  int rc = -1;
  std::string out = runCapture("EHC_SKIP_SETUP=1 bash " + kScript + " --dry-run controller 2>&1", rc);
  EXPECT_NE(out.find("rosrun ehc_control ehc_controller_node _config:=config/realman/controller.yaml"
                     " _robot:=config/robots/realman_rm65_water2/robot.yaml _trigger:=timer"), std::string::npos) << out;
  // The simulator's lock-step configuration (node.trigger: state, possibly through extends:)
  // would never cycle on the robot: the controller runs it on its timer (the loader decides,
  // not a text search of the file).
  out = runCapture("EHC_SKIP_SETUP=1 CONTROLLER_CONFIG=config/control/controller.yaml CONTROLLER_MODE=tsmm"
                   " bash " + kScript + " --dry-run controller 2>&1", rc);
  EXPECT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("_config:=config/control/controller.yaml _robot:=config/robots/realman_rm65_water2/robot.yaml"
                     " _trigger:=timer _mode:=tsmm"), std::string::npos) << out;
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

  // Leftovers of an earlier run on this master (an earlier
  // CONTROLLER_MODE=tsmm stayed in force): the script deletes each node's private namespace.
  ros::param::set("/rm_arm_adapter/left_by_an_earlier_run", 1);
  ros::param::set("/water2_base_bridge/left_by_an_earlier_run", 1);
  ros::param::set("/robot_state_publisher/left_by_an_earlier_run", 1);
  ros::param::set("/rm_arm_adapter_other/kept", 1);  // a namespace that only shares the prefix

  tf2_ros::Buffer tf_buffer;
  tf2_ros::TransformListener tf_listener(tf_buffer);
  ros::Publisher joint_states = nh.advertise<sensor_msgs::JointState>("/joint_states", 10);
  const ehc_control::RobotConfig robot = ehc_control::loadRobotConfig(
      std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/robot.yaml");
  const ehc_control::WholeBodyModel model(robot);

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
  for (const char* stale : {"/rm_arm_adapter/left_by_an_earlier_run",
                            "/water2_base_bridge/left_by_an_earlier_run",
                            "/robot_state_publisher/left_by_an_earlier_run"})
    EXPECT_FALSE(ros::param::has(stale)) << stale << " survived into this run";
  EXPECT_TRUE(ros::param::has("/rm_arm_adapter_other/kept"));

  // robot_state_publisher: the driver's /joint_states (stand-in: this test) -> arm tf.
  sensor_msgs::JointState js;
  js.name = robot.arm_joints;
  js.position.assign(robot.arm_ready.data(), robot.arm_ready.data() + robot.arm_ready.size());
  js.name.insert(js.name.end(), {"left_finger_joint", "right_finger_joint"});
  js.position.insert(js.position.end(), {0.02, 0.02});
  const bool tf_up = waitFor([&] {
    js.header.stamp = ros::Time::now();
    joint_states.publish(js);
    return tf_buffer.canTransform(robot.base_frame, robot.camera_frame, ros::Time(0));
  }, 30.0);
  EXPECT_TRUE(tf_up) << "no tf " << robot.base_frame << " -> " << robot.camera_frame;
  if (tf_up) {
    const auto t = tf_buffer.lookupTransform(robot.base_frame, robot.camera_frame, ros::Time(0));
    const Eigen::Isometry3d expected = model.linkPoseInBase(robot.arm_ready, robot.camera_frame);
    const auto& tr = t.transform.translation;
    const auto& r = t.transform.rotation;
    EXPECT_LT((Eigen::Vector3d(tr.x, tr.y, tr.z) - expected.translation()).norm(), 1e-4);
    EXPECT_LT(Eigen::Quaterniond(r.w, r.x, r.y, r.z).angularDistance(
                  Eigen::Quaterniond(expected.linear())), 1e-4);
  }

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
