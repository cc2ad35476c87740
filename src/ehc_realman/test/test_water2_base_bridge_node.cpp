// rostest: water2_base_bridge node against FakeWater2Server on 127.0.0.1, on sim time that this
// test owns (/use_sim_time in the .test file). This test node picks a free loopback port, starts
// the fake server on its own sim clock, then runs the bridge node itself with rosrun-style
// arguments (_config, _host, _port, _status_every_step:=true) and stops it (by its pid) at the end.
// Lock-step: every step advances /clock by the bridge's network cycle (10 ms), publishes
// /cmd_vel when the controller would, waits for the bridge's status of that cycle ("last_step")
// and then until the server has handled every request the status counts. So each request is
// attributed to the sim time of the cycle that sent it, whatever the machine's load; /odom is
// timed by its header stamp (the bridge's clock). The only wall clock is a hang guard.
// Checks: /odom + tf from robot_status, request rate and clamping, zero after /cmd_vel stops
// (on the bridge's clock), server killed mid-run => /odom withheld, ERROR status, zero first
// after the reconnection, malformed replies survived.

#include "water2_fake_server.h"

#include "ehc_control/pose_math.h"
#include "ehc_realman/water2_base_bridge.h"

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>

#include <gtest/gtest.h>

#include "sim_clock_wait.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>

using ehc_realman_test::FakeWater2Server;

namespace {

using ehc_realman_test::spinUntil;

constexpr double kStep = 0.01;       ///< s of sim time per step (the bridge's network cycle)
const std::string kConfig = std::string(EHC_CONFIG_DIR) + "/../src/ehc_realman/test/water2_loopback.yaml";

/// The test's sim time, shared with the fake server's thread (integer steps: no drift).
std::atomic<long> g_steps{0};
double simNow() { return 100.0 + static_cast<double>(g_steps.load()) * kStep; }

class Rig {
 public:
  Rig(ros::NodeHandle& nh, FakeWater2Server& server) : server_(server) {
    clock_pub_ = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
    cmd_pub_ = nh.advertise<geometry_msgs::Twist>("/cmd_vel", 10);
    odom_sub_ = nh.subscribe("/odom", 1000, &Rig::onOdom, this);
    status_sub_ = nh.subscribe("/water2/status", 1000, &Rig::onStatus, this,
                               ros::TransportHints().tcpNoDelay());
  }

  bool connected() {
    return spinUntil([&] {
      return cmd_pub_.getNumSubscribers() > 0 && clock_pub_.getNumSubscribers() > 0 &&
             status_sub_.getNumPublishers() > 0 && odom_sub_.getNumPublishers() > 0;
    }, "connection to water2_base_bridge");
  }

  /// One network cycle of sim time; /cmd_vel (v, w) if given. See the file comment.
  bool step(const std::optional<std::pair<double, double>>& cmd = std::nullopt) {
    ++g_steps;
    const double t = simNow();
    rosgraph_msgs::Clock c;
    c.clock = ros::Time(100, 0) + ros::Duration(kStep * static_cast<double>(g_steps.load()));
    clock_pub_.publish(c);
    if (cmd) {
      geometry_msgs::Twist tw;
      tw.linear.x = cmd->first;
      tw.angular.z = cmd->second;
      cmd_pub_.publish(tw);
      ++commands_sent_;
    }
    // The cycle's status and the command's receipt (this cycle or the previous one: it may be
    // taken before this cycle's /clock, never later).
    if (!spinUntil([&] {
          return last_step_ >= t - 1e-6 &&
                 count("commands") + count("rejected_commands") >= commands_sent_;
        }, "status of the network cycle and the command", [&] { clock_pub_.publish(c); }))
      return false;
    noteConnection();
    return spinUntil([&] {
      return !server_.running() || status_.level == diagnostic_msgs::DiagnosticStatus::ERROR ||
             server_.handled() >= count("joy_requests") + count("status_requests") - base_;
    }, "server handshake");
  }
  /// Steps for `seconds`, publishing (v, w) at 20 Hz like a controller (every 5th step).
  bool drive(double v, double w, double seconds) {
    const int n = static_cast<int>(std::lround(seconds / kStep));
    for (int k = 0; k < n; ++k) {
      const bool send = k % 5 == 0;
      if (!step(send ? std::optional<std::pair<double, double>>({v, w}) : std::nullopt)) return false;
      if (send) last_command_ = simNow();
    }
    return true;
  }
  bool stepFor(double seconds) {
    const int n = static_cast<int>(std::lround(seconds / kStep));
    for (int k = 0; k < n; ++k)
      if (!step()) return false;
    return true;
  }
  /// Steps (driving (v, w) at 20 Hz if given) until `done` or `seconds` of sim time pass.
  bool stepUntil(const std::function<bool()>& done, double seconds,
                 std::optional<std::pair<double, double>> cmd = std::nullopt) {
    const int n = static_cast<int>(std::lround(seconds / kStep));
    for (int k = 0; k < n && !done(); ++k)
      if (!step(cmd && k % 5 == 0 ? cmd : std::nullopt)) return false;
    return done();
  }

  /// /odom stamped in [t0, t1] (the bridge's clock).
  std::vector<nav_msgs::Odometry> odomBetween(double t0, double t1) const {
    std::vector<nav_msgs::Odometry> out;
    for (const auto& o : odom_)
      if (o.header.stamp.toSec() >= t0 - 1e-9 && o.header.stamp.toSec() <= t1 + 1e-9) out.push_back(o);
    return out;
  }
  /// Waits until /odom stamped at or after `t` arrived (it is published at 50 Hz of sim time).
  bool odomUpTo(double t) {
    return spinUntil([&] { return !odom_.empty() && odom_.back().header.stamp.toSec() >= t - 1e-6; },
                     "/odom up to now");
  }
  bool odomFresh() const { return !odom_.empty() && odom_.back().header.stamp.toSec() >= simNow() - 0.1; }
  int level() const { return status_.level; }
  unsigned long count(const std::string& key) const {
    for (const auto& kv : status_.values)
      if (kv.key == key) return kv.value.empty() ? 0ul : std::stoul(kv.value);
    return 0ul;
  }
  double lastCommand() const { return last_command_; }

 private:
  void onOdom(const nav_msgs::Odometry::ConstPtr& m) { odom_.push_back(*m); }
  void onStatus(const diagnostic_msgs::DiagnosticStatus::ConstPtr& m) {
    double last_step = -1.0;
    for (const auto& kv : m->values)
      if (kv.key == "last_step") last_step = std::stod(kv.value);
    if (!std::isfinite(last_step) || last_step < last_step_) return;
    status_ = *m;
    last_step_ = last_step;
  }
  /// A new connection: what was sent on the old one was handled or is lost with it.
  void noteConnection() {
    const unsigned long connects = count("connects");
    if (connects != connects_) {
      connects_ = connects;
      base_ = count("joy_requests") + count("status_requests") - server_.handled();
    }
  }

  FakeWater2Server& server_;
  ros::Publisher clock_pub_, cmd_pub_;
  ros::Subscriber odom_sub_, status_sub_;
  std::vector<nav_msgs::Odometry> odom_;
  diagnostic_msgs::DiagnosticStatus status_;
  double last_step_ = -1.0;
  unsigned long connects_ = 0, base_ = 0, commands_sent_ = 0;
  double last_command_ = 0.0;
};

FakeWater2Server* g_server = nullptr;
Rig* g_rig = nullptr;
pid_t g_bridge = -1;

bool bridgeAlive() { return g_bridge > 0 && ::waitpid(g_bridge, nullptr, WNOHANG) == 0; }

}  // namespace

TEST(Water2BaseBridgeNode, PublishesOdometryFromTheStatusStream) {
  Rig& r = *g_rig;
  g_server->setPose(1.0, 2.0, 0.5);
  ASSERT_TRUE(r.stepFor(1.0));  // the next robot_status (every 0.5 s) carries the new pose
  const double t0 = simNow();
  ASSERT_TRUE(r.stepFor(2.0));
  ASSERT_TRUE(r.odomUpTo(simNow() - 0.02));
  const auto odom = r.odomBetween(t0, t0 + 2.0);
  EXPECT_GE(odom.size(), 99u) << "configured 50 Hz for 2 s of sim time";
  EXPECT_LE(odom.size(), 101u);
  for (const auto& o : odom) {
    EXPECT_EQ(o.header.frame_id, "odom");
    EXPECT_EQ(o.child_frame_id, "base_link");
    EXPECT_NEAR(o.pose.pose.position.x, 1.0, 1e-6);
    EXPECT_NEAR(o.pose.pose.position.y, 2.0, 1e-6);
    const auto& q = o.pose.pose.orientation;
    EXPECT_NEAR(ehc_control::yawFromQuaternion(Eigen::Quaterniond(q.w, q.x, q.y, q.z)), 0.5, 1e-6);
  }
  EXPECT_EQ(r.level(), diagnostic_msgs::DiagnosticStatus::OK);
}

TEST(Water2BaseBridgeNode, ForwardsClampedCommandsAtRateAndStopsAfterTimeout) {
  Rig& r = *g_rig;
  g_server->clearRequests();
  const double t0 = simNow();
  ASSERT_TRUE(r.drive(0.8, 0.5, 2.0));  // |v| > 0.5: scaled by 0.625 => (0.5, 0.3125)
  const double t_last = r.lastCommand();
  ASSERT_TRUE(r.stepFor(1.5));
  int moving = 0, zeros_after = 0;
  double first_moving = -1.0, last_moving = t0, first_zero = -1.0;
  for (const auto& q : g_server->requests()) {
    if (!q.joy) continue;
    EXPECT_LE(std::abs(q.linear), 0.5 + 1e-9);
    EXPECT_LE(std::abs(q.angular), 1.0 + 1e-9);
    if (q.linear != 0.0) {
      ++moving;
      if (first_moving < 0.0) first_moving = q.time;
      last_moving = q.time;
      EXPECT_NEAR(q.linear, 0.5, 1e-4);
      EXPECT_NEAR(q.angular, 0.3125, 1e-4);
    } else if (q.time > t_last) {
      ++zeros_after;
      if (first_zero < 0.0) first_zero = q.time;
    }
  }
  ASSERT_GT(moving, 1);
  EXPECT_NEAR((last_moving - first_moving) / (moving - 1), 0.05, 1e-6) << "20 Hz of sim time";
  // The timeout on the bridge's clock, from the receipt of the last /cmd_vel (that cycle or the
  // previous one): no motion request after it, a zero at the next cycle, zeros for 1 s.
  const double timeout = ehc_realman::loadWater2BridgeConfig(kConfig).command_timeout;
  EXPECT_LE(last_moving, t_last + timeout + 1e-6) << "no motion request after the timeout";
  ASSERT_GT(first_zero, 0.0);
  EXPECT_GT(first_zero - t_last, timeout - 2 * kStep - 1e-6);  // receipt a step early; rounding
  EXPECT_LE(first_zero - t_last, timeout + 2 * kStep + 1e-6) << "zero within one cycle of the timeout";
  EXPECT_GE(zeros_after, 20);
  std::printf("[water2_base_bridge] lock-step: %d moving requests, first zero %.3f s (sim) after the last "
              "/cmd_vel (command_timeout %.2f s)\n", moving, first_zero - t_last, timeout);
  EXPECT_GT(r.count("clamped_commands"), 0ul);
  // The fake base moved and /odom follows it.
  double x, y, th;
  g_server->pose(x, y, th);
  ASSERT_TRUE(r.odomUpTo(simNow() - 0.02));
  const auto odom = r.odomBetween(simNow() - 0.1, simNow());
  ASSERT_FALSE(odom.empty());
  EXPECT_NEAR(odom.back().pose.pose.position.x, x, 0.05);
  EXPECT_NEAR(odom.back().pose.pose.position.y, y, 0.05);
}

TEST(Water2BaseBridgeNode, ServerKilledMidRunMeansZeroMotionAndReconnect) {
  Rig& r = *g_rig;
  const std::pair<double, double> cmd{0.3, 0.0};
  ASSERT_TRUE(r.drive(cmd.first, cmd.second, 1.0));
  const unsigned long losses = r.count("connection_losses");
  g_server->stop();  // killed while commands keep coming
  ASSERT_TRUE(r.stepUntil([&] { return r.level() == diagnostic_msgs::DiagnosticStatus::ERROR; }, 3.0, cmd))
      << "ERROR status on connection loss";
  ASSERT_TRUE(r.drive(cmd.first, cmd.second, 2.0));  // status_timeout (1.5 s) passes
  EXPECT_TRUE(r.odomBetween(simNow() - 0.5, simNow()).empty()) << "no stale /odom";
  EXPECT_TRUE(bridgeAlive()) << "the bridge must not crash";
  g_server->clearRequests();
  g_server->start();  // same port
  EXPECT_TRUE(r.stepUntil([&] { return r.level() == diagnostic_msgs::DiagnosticStatus::OK; }, 5.0, cmd));
  EXPECT_TRUE(r.stepUntil([&] { return r.odomFresh(); }, 3.0, cmd));
  ASSERT_TRUE(r.drive(cmd.first, cmd.second, 0.5));
  EXPECT_GE(r.count("connection_losses"), losses + 1);
  bool first = true;
  for (const auto& q : g_server->requests()) {
    if (!q.joy) continue;
    if (first) {
      EXPECT_EQ(q.linear, 0.0) << "first command after reconnecting must be zero";
    }
    first = false;
  }
  EXPECT_FALSE(first) << "commands resumed after the reconnection";
}

TEST(Water2BaseBridgeNode, MalformedRepliesAreSurvived) {
  Rig& r = *g_rig;
  using Mode = FakeWater2Server::ReplyMode;
  const unsigned long malformed = r.count("malformed_replies");
  for (Mode m : {Mode::BadJson, Mode::Garbage, Mode::BadPose, Mode::Truncated, Mode::Oversized}) {
    g_server->setReplyMode(m);
    ASSERT_TRUE(r.drive(0.1, 0.1, 1.0));
    g_server->setReplyMode(Mode::Normal);
    EXPECT_TRUE(r.stepUntil([&] { return r.odomFresh(); }, 6.0, std::make_pair(0.1, 0.1)))
        << "odometry recovers after mode " << static_cast<int>(m);
    EXPECT_TRUE(bridgeAlive());
  }
  EXPECT_GT(r.count("malformed_replies"), malformed);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_water2_base_bridge_node");
  ros::NodeHandle nh;

  FakeWater2Server server(0, &simNow);  // 127.0.0.1, free port, this test's sim clock
  server.start();
  g_server = &server;
  Rig rig(nh, server);
  g_rig = &rig;

  // Run the bridge node (rosrun-style arguments); it inherits ROS_MASTER_URI from rostest and
  // /use_sim_time from the .test file.
  const std::string a_config = "_config:=" + kConfig;
  const std::string a_host = "_host:=127.0.0.1";
  const std::string a_port = "_port:=" + std::to_string(server.port());
  const std::string a_step = "_status_every_step:=true";
  const std::string a_name = "__name:=water2_base_bridge";
  g_bridge = ::fork();
  if (g_bridge == 0) {
    ::execl(WATER2_BRIDGE_BIN, WATER2_BRIDGE_BIN, a_config.c_str(), a_host.c_str(),
            a_port.c_str(), a_step.c_str(), a_name.c_str(), static_cast<char*>(nullptr));
    std::_Exit(127);
  }
  int rc = 1;
  if (g_bridge < 0) {
    ADD_FAILURE() << "fork failed";
  } else if (!rig.connected() ||
             !rig.stepUntil([&] { return rig.odomFresh(); }, 10.0)) {  // connected to the server
    ADD_FAILURE() << "water2_base_bridge did not come up (topics, server, /odom)";
  } else {
    rc = RUN_ALL_TESTS();
  }
  if (g_bridge > 0) {  // stop our own child, by pid: SIGINT, then SIGKILL if it hangs
    ::kill(g_bridge, SIGINT);
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(5.0);
    while (::waitpid(g_bridge, nullptr, WNOHANG) != g_bridge && ros::WallTime::now() < end)
      ros::WallDuration(0.01).sleep();
    if (::waitpid(g_bridge, nullptr, WNOHANG) == 0) {
      ::kill(g_bridge, SIGKILL);
      ::waitpid(g_bridge, nullptr, 0);
    }
  }
  server.stop();
  return rc;
}
