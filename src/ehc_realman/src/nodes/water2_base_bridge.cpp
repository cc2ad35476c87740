// water2_base_bridge: /cmd_vel -> Water2 joy_control over TCP (clamped, resent while fresh,
// zero after a timeout), /odom + tf odom->base_link from the base's robot_status replies
// (withheld when stale), reconnection with back-off. Thin wrapper around
// ehc_realman::Water2BaseBridge; the network work runs in its own thread.
//
//   rosrun ehc_realman water2_base_bridge _config:=config/realman/water2_base_bridge.yaml
//       [_host:=192.168.10.10] [_port:=31001]   (one line)
//
// Subscribes: /cmd_vel (geometry_msgs/Twist; linear.x, angular.z)
// Publishes:  /odom (nav_msgs/Odometry), tf odom->base_link,
//             /water2/status (diagnostic_msgs/DiagnosticStatus: OK / WARN stale / ERROR link;
//             key "last_step": the node-clock time of the last network cycle under sim time)
// Clock (node_clock.h): steady on the robot, the network work in its own thread; ROS time under
// /use_sim_time, one network cycle per 10 ms of ROS time on a ROS timer (replies read in the
// next cycle). `_status_every_step:=true` publishes the status after every such cycle and every
// /cmd_vel (a lock-step test's handshake: the request counters say what that cycle sent,
// "commands" + "rejected_commands" that a command was taken).

#include "ehc_common/logging.h"
#include "ehc_common/node_init.h"
#include "ehc_realman/water2_base_bridge.h"
#include "diagnostics.h"
#include "node_clock.h"

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <tf2_ros/transform_broadcaster.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <sstream>
#include <thread>

namespace {

using ehc_common::kLogThrottle;
constexpr double kSimCyclePeriod = 0.01;  ///< s of ROS time per network cycle under sim time

using ehc_realman_nodes::kv;

class Water2BaseBridgeNode {
 public:
  Water2BaseBridgeNode(ros::NodeHandle& nh, const ehc_realman::Water2BridgeConfig& config,
                       bool status_every_step)
      : bridge_(config, [] { return ehc_realman_nodes::nodeNow(); }),
        status_every_step_(status_every_step) {
    odom_pub_ = nh.advertise<nav_msgs::Odometry>("/odom", 10);
    status_pub_ = nh.advertise<diagnostic_msgs::DiagnosticStatus>("/water2/status", 1, true);
    cmd_sub_ = nh.subscribe("/cmd_vel", 10, &Water2BaseBridgeNode::onCmdVel, this,
                            ros::TransportHints().tcpNoDelay());
    odom_timer_ = ehc_realman_nodes::NodeTimer(nh, 1.0 / config.odom_rate_hz, [this] { publishOdometry(); });
    status_timer_ = ehc_realman_nodes::NodeTimer(nh, 1.0 / config.status_rate_hz, [this] { publishStatus(); });
    if (ros::Time::isSimTime())
      network_timer_ = ehc_realman_nodes::NodeTimer(nh, kSimCyclePeriod, [this] { networkCycle(); });
    else
      network_thread_ = std::thread([this] {
        while (running_ && ros::ok()) bridge_.spinOnce(0.02);
      });
  }

  ~Water2BaseBridgeNode() {
    running_ = false;
    if (network_thread_.joinable()) network_thread_.join();
  }

 private:
  void onCmdVel(const geometry_msgs::Twist::ConstPtr& msg) {
    if (msg->linear.y != 0.0 || msg->angular.x != 0.0 || msg->angular.y != 0.0 ||
        msg->linear.z != 0.0)
      ROS_WARN_THROTTLE(kLogThrottle, "water2_base_bridge: differential base: only linear.x and "
                             "angular.z of /cmd_vel are used");
    try {
      bridge_.setCommand(msg->linear.x, msg->angular.z);
    } catch (const std::exception& e) {
      ROS_ERROR_THROTTLE(kLogThrottle, "water2_base_bridge: /cmd_vel rejected: %s", e.what());
    }
    if (status_every_step_) publishStatus();  // the command's receipt, for a lock-step test
  }

  /// Sim time: one bounded network cycle per instant of ROS time (no waiting for replies).
  void networkCycle() {
    const double now = ehc_realman_nodes::nodeNow();
    if (now <= last_step_time_) return;  // a ROS timer may fire twice when /clock jumps
    bridge_.spinOnce(0.0);
    last_step_time_ = now;
    if (status_every_step_) publishStatus();
  }

  void publishOdometry() {
    const auto odom = bridge_.odometry();
    if (!odom) return;  // no fresh status: publish nothing rather than stale data
    const auto& c = bridge_.config();
    const ros::Time stamp = ros::Time::now();
    nav_msgs::Odometry o;
    o.header.stamp = stamp;
    o.header.frame_id = c.odom_frame;
    o.child_frame_id = c.base_frame;
    o.pose.pose.position.x = odom->x;
    o.pose.pose.position.y = odom->y;
    o.pose.pose.orientation.z = std::sin(0.5 * odom->theta);
    o.pose.pose.orientation.w = std::cos(0.5 * odom->theta);
    o.twist.twist.linear.x = odom->linear;
    o.twist.twist.angular.z = odom->angular;
    o.pose.covariance[0] = o.pose.covariance[7] = odom->positionVariance();
    o.pose.covariance[14] = o.pose.covariance[21] = o.pose.covariance[28] = 1e6;  // z, roll, pitch
    o.pose.covariance[35] = odom->yawVariance();
    o.twist.covariance[0] = 0.01;
    o.twist.covariance[35] = 0.01;
    odom_pub_.publish(o);

    geometry_msgs::TransformStamped t;
    t.header = o.header;
    t.child_frame_id = c.base_frame;
    t.transform.translation.x = odom->x;
    t.transform.translation.y = odom->y;
    t.transform.rotation = o.pose.pose.orientation;
    tf_.sendTransform(t);
  }

  void publishStatus() {
    const auto s = bridge_.status();
    diagnostic_msgs::DiagnosticStatus d;
    d.name = "water2_base_bridge";
    d.hardware_id = bridge_.config().host + ":" + std::to_string(bridge_.config().port);
    using Level = ehc_realman::Water2BridgeStatus::Level;
    d.level = s.level == Level::Ok     ? diagnostic_msgs::DiagnosticStatus::OK
              : s.level == Level::Warn ? diagnostic_msgs::DiagnosticStatus::WARN
                                       : diagnostic_msgs::DiagnosticStatus::ERROR;
    d.message = s.message;
    std::ostringstream age;
    age << s.status_age;
    d.values = {kv("connected", s.connected ? "true" : "false"), kv("status_age", age.str()),
                kv("connects", std::to_string(s.connects)),
                kv("connection_losses", std::to_string(s.connection_losses)),
                kv("failed_connects", std::to_string(s.failed_connects)),
                kv("joy_requests", std::to_string(s.joy_requests)),
                kv("status_requests", std::to_string(s.status_requests)),
                kv("replies", std::to_string(s.replies)),
                kv("malformed_replies", std::to_string(s.malformed_replies)),
                kv("error_replies", std::to_string(s.error_replies)),
                kv("clamped_commands", std::to_string(s.clamped_commands)),
                kv("commands", std::to_string(s.commands)),
                kv("rejected_commands", std::to_string(s.rejected_commands)),
                kv("last_error", s.last_error), kv("last_step", lastStepText())};
    status_pub_.publish(d);
    if (s.level != last_level_) {
      if (s.level == Level::Ok) ROS_INFO("water2_base_bridge: %s", s.message.c_str());
      else if (s.level == Level::Warn) ROS_WARN("water2_base_bridge: %s", s.message.c_str());
      else ROS_ERROR("water2_base_bridge: %s", s.message.c_str());
      last_level_ = s.level;
    }
  }

  std::string lastStepText() const {
    char text[32];
    std::snprintf(text, sizeof(text), "%.9f", last_step_time_.load());
    return text;
  }

  ehc_realman::Water2BaseBridge bridge_;
  const bool status_every_step_;
  std::atomic<double> last_step_time_{-std::numeric_limits<double>::infinity()};  ///< sim time only
  ros::Publisher odom_pub_, status_pub_;
  ros::Subscriber cmd_sub_;
  ehc_realman_nodes::NodeTimer odom_timer_, status_timer_, network_timer_;
  tf2_ros::TransformBroadcaster tf_;
  ehc_realman::Water2BridgeStatus::Level last_level_ = ehc_realman::Water2BridgeStatus::Level::Ok;
  std::atomic<bool> running_{true};
  std::thread network_thread_;
};

}  // namespace

int main(int argc, char** argv) {
  return ehc_common::runNode(argc, argv, "water2_base_bridge", 2, [](const ehc_common::NodeParams& params, ros::NodeHandle& nh) {
    ehc_realman::Water2BridgeConfig config;
    if (const auto path = params.getOptional<std::string>("config"))
      config = ehc_realman::loadWater2BridgeConfig(*path);
    else
      ROS_WARN("water2_base_bridge: no _config:=<file.yaml>; using built-in defaults");
    config.host = params.get("host", config.host);
    config.port = params.getInRange("port", config.port, 1, 65535);
    params.validate([&] { config.validate(); });
    const bool status_every_step = params.get("status_every_step", false);
    ehc_common::checkNodeParams(params);
    ROS_INFO_STREAM("water2_base_bridge configuration:\n" << config.summary() << "\nclock: "
                    << (ros::Time::isSimTime() ? "ROS time (/use_sim_time), network cycle every 10 ms" : "steady")
                    << (status_every_step ? ", status after every network cycle" : ""));
    auto node = std::make_unique<Water2BaseBridgeNode>(nh, config, status_every_step);
    ros::spin();
    node.reset();
    return 0;
  });
}
