// rostest: water2_base_bridge node against FakeWater2Server on 127.0.0.1. This test node picks a
// free loopback port, starts the fake server, then runs the bridge node itself with rosrun-style
// arguments (_config, _host, _port) and stops it (by its pid) at the end.
// Checks: /odom + tf from robot_status, request rate and clamping, zero after /cmd_vel stops,
// server killed mid-run => /odom withheld, ERROR status, zero first after the reconnection,
// malformed replies survived. Waits are bounded; timing tolerances are generous.

#include "water2_fake_server.h"

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <functional>
#include <mutex>
#include <thread>

using ehc_realman_test::FakeWater2Server;

namespace {

using ehc_realman_test::now;
using ehc_realman_test::sleepFor;
using ehc_realman_test::waitFor;

struct Observed {
  std::mutex mutex;
  std::vector<std::pair<double, nav_msgs::Odometry>> odom;
  diagnostic_msgs::DiagnosticStatus status;
  double status_time = 0.0;

  std::vector<nav_msgs::Odometry> odomSince(double t0) {
    std::lock_guard<std::mutex> lock(mutex);
    std::vector<nav_msgs::Odometry> out;
    for (const auto& o : odom)
      if (o.first >= t0) out.push_back(o.second);
    return out;
  }
  int level() {
    std::lock_guard<std::mutex> lock(mutex);
    return status.level;
  }
  std::string value(const std::string& key) {
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& kv : status.values)
      if (kv.key == key) return kv.value;
    return "";
  }
  unsigned long count(const std::string& key) {
    const std::string v = value(key);
    return v.empty() ? 0ul : std::stoul(v);
  }
};

FakeWater2Server* g_server = nullptr;
Observed* g_seen = nullptr;
ros::Publisher g_cmd;
pid_t g_bridge = -1;

bool bridgeAlive() { return g_bridge > 0 && ::waitpid(g_bridge, nullptr, WNOHANG) == 0; }

void drive(double v, double w, double seconds) {
  geometry_msgs::Twist t;
  t.linear.x = v;
  t.angular.z = w;
  const double end = now() + seconds;
  while (now() < end) {
    g_cmd.publish(t);
    sleepFor(0.05);  // 20 Hz, like a controller
  }
}

}  // namespace

TEST(Water2BaseBridgeNode, PublishesOdometryFromTheStatusStream) {
  g_server->setPose(1.0, 2.0, 0.5);
  ASSERT_TRUE(waitFor([] { return !g_seen->odomSince(now() - 0.2).empty(); }, 10.0));
  sleepFor(1.0);
  const double t0 = now();
  sleepFor(2.0);
  const auto odom = g_seen->odomSince(t0);
  EXPECT_GE(odom.size(), 50u) << "configured 50 Hz for 2 s";
  for (const auto& o : odom) {
    EXPECT_EQ(o.header.frame_id, "odom");
    EXPECT_EQ(o.child_frame_id, "base_link");
    EXPECT_NEAR(o.pose.pose.position.x, 1.0, 1e-6);
    EXPECT_NEAR(o.pose.pose.position.y, 2.0, 1e-6);
    EXPECT_NEAR(2.0 * std::atan2(o.pose.pose.orientation.z, o.pose.pose.orientation.w), 0.5, 1e-6);
  }
  EXPECT_EQ(g_seen->level(), diagnostic_msgs::DiagnosticStatus::OK);
}

TEST(Water2BaseBridgeNode, ForwardsClampedCommandsAtRateAndStopsAfterTimeout) {
  g_server->clearRequests();
  const double t0 = now();
  drive(0.8, 0.5, 2.0);  // |v| > 0.5: scaled by 0.625 => (0.5, 0.3125)
  const double t_last = now();
  sleepFor(1.5);
  int moving = 0, zeros_after = 0;
  double last_moving = t0, first_zero = -1.0;
  for (const auto& r : g_server->requests()) {
    if (!r.joy) continue;
    EXPECT_LE(std::abs(r.linear), 0.5 + 1e-9);
    EXPECT_LE(std::abs(r.angular), 1.0 + 1e-9);
    if (r.linear != 0.0) {
      ++moving;
      last_moving = r.time;
      EXPECT_NEAR(r.linear, 0.5, 1e-4);
      EXPECT_NEAR(r.angular, 0.3125, 1e-4);
    } else if (r.time > t_last - 0.05) {
      ++zeros_after;
      if (first_zero < 0.0) first_zero = r.time;
    }
  }
  const double rate = moving / std::max(1e-3, last_moving - t0);
  EXPECT_GE(rate, 10.0) << moving << " joy_control requests in " << last_moving - t0 << " s";
  EXPECT_LE(last_moving - t_last, 0.15 + 0.25) << "no motion request after the timeout";
  ASSERT_GT(first_zero, 0.0);
  EXPECT_LE(first_zero - t_last, 0.2 + 0.25) << "zero sent within 0.2 s (+ CI margin)";
  EXPECT_GE(zeros_after, 5);
  EXPECT_GT(g_seen->count("clamped_commands"), 0ul);
  // The fake base moved and /odom follows it.
  double x, y, th;
  g_server->pose(x, y, th);
  const auto odom = g_seen->odomSince(now() - 0.1);
  ASSERT_FALSE(odom.empty());
  EXPECT_NEAR(odom.back().pose.pose.position.x, x, 0.05);
  EXPECT_NEAR(odom.back().pose.pose.position.y, y, 0.05);
}

TEST(Water2BaseBridgeNode, ServerKilledMidRunMeansZeroMotionAndReconnect) {
  std::thread controller([] { drive(0.3, 0.0, 6.0); });
  sleepFor(1.0);
  const unsigned long losses = g_seen->count("connection_losses");
  g_server->stop();  // killed while commands keep coming
  const double t_kill = now();
  EXPECT_TRUE(waitFor([] { return g_seen->level() == diagnostic_msgs::DiagnosticStatus::ERROR; },
                      3.0)) << "ERROR status on connection loss";
  sleepFor(std::max(0.0, t_kill + 2.0 - now()));
  EXPECT_TRUE(g_seen->odomSince(now() - 0.5).empty()) << "no stale /odom";
  EXPECT_TRUE(bridgeAlive()) << "the bridge must not crash";
  g_server->clearRequests();
  g_server->start();  // same port
  EXPECT_TRUE(waitFor([] { return g_seen->level() == diagnostic_msgs::DiagnosticStatus::OK; }, 5.0));
  EXPECT_TRUE(waitFor([] { return !g_seen->odomSince(now() - 0.2).empty(); }, 3.0));
  controller.join();
  EXPECT_GE(g_seen->count("connection_losses"), losses + 1);
  bool first = true;
  for (const auto& r : g_server->requests()) {
    if (!r.joy) continue;
    if (first) {
      EXPECT_EQ(r.linear, 0.0) << "first command after reconnecting must be zero";
    }
    first = false;
  }
  EXPECT_FALSE(first) << "commands resumed after the reconnection";
}

TEST(Water2BaseBridgeNode, MalformedRepliesAreSurvived) {
  using Mode = FakeWater2Server::ReplyMode;
  const unsigned long malformed = g_seen->count("malformed_replies");
  for (Mode m : {Mode::BadJson, Mode::Garbage, Mode::BadPose, Mode::Truncated, Mode::Oversized}) {
    g_server->setReplyMode(m);
    drive(0.1, 0.1, 1.0);
    g_server->setReplyMode(Mode::Normal);
    EXPECT_TRUE(waitFor([] { return !g_seen->odomSince(now() - 0.1).empty(); }, 6.0))
        << "odometry recovers after mode " << static_cast<int>(m);
    EXPECT_TRUE(bridgeAlive());
  }
  EXPECT_TRUE(waitFor([&] { return g_seen->count("malformed_replies") > malformed; }, 2.0));
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_water2_base_bridge_node");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();

  FakeWater2Server server;  // 127.0.0.1, free port
  server.start();
  g_server = &server;
  Observed seen;
  g_seen = &seen;
  auto odom_sub = nh.subscribe<nav_msgs::Odometry>("/odom", 100, boost::function<void(const nav_msgs::Odometry::ConstPtr&)>([](const nav_msgs::Odometry::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(g_seen->mutex);
    g_seen->odom.emplace_back(now(), *m);
  }));
  auto status_sub = nh.subscribe<diagnostic_msgs::DiagnosticStatus>(
      "/water2/status", 10, boost::function<void(const diagnostic_msgs::DiagnosticStatus::ConstPtr&)>([](const diagnostic_msgs::DiagnosticStatus::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(g_seen->mutex);
        g_seen->status = *m;
        g_seen->status_time = now();
      }));
  g_cmd = nh.advertise<geometry_msgs::Twist>("/cmd_vel", 10);

  // Run the bridge node (rosrun-style arguments); it inherits ROS_MASTER_URI from rostest.
  const std::string config = std::string(EHC_CONFIG_DIR) + "/../src/ehc_realman/test/water2_loopback.yaml";
  const std::string a_config = "_config:=" + config;
  const std::string a_host = "_host:=127.0.0.1";
  const std::string a_port = "_port:=" + std::to_string(server.port());
  const std::string a_name = "__name:=water2_base_bridge";
  g_bridge = ::fork();
  if (g_bridge == 0) {
    ::execl(WATER2_BRIDGE_BIN, WATER2_BRIDGE_BIN, a_config.c_str(), a_host.c_str(),
            a_port.c_str(), a_name.c_str(), static_cast<char*>(nullptr));
    std::_Exit(127);
  }
  int rc = 1;
  if (g_bridge < 0) {
    ADD_FAILURE() << "fork failed";
  } else if (!waitFor([] { return g_cmd.getNumSubscribers() > 0; }, 30.0)) {
    ADD_FAILURE() << "water2_base_bridge did not subscribe to /cmd_vel within 30 s";
  } else {
    rc = RUN_ALL_TESTS();
  }
  if (g_bridge > 0) {  // stop our own child, by pid: SIGINT, then SIGKILL if it hangs
    ::kill(g_bridge, SIGINT);
    if (!waitFor([] { return ::waitpid(g_bridge, nullptr, WNOHANG) == g_bridge; }, 5.0)) {
      ::kill(g_bridge, SIGKILL);
      ::waitpid(g_bridge, nullptr, 0);
    }
  }
  server.stop();
  spinner.stop();
  return rc;
}
