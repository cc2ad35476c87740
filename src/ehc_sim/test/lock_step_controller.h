#pragma once
// LockStepController: the fake controller of the fake-robot rostests (ehc_sim_node,
// ehc_kinematic_sim_node). It reads the state a simulator publishes (/joint_states, /odom,
// /sim/status, /clock) and answers each state with /cmd_vel then /arm/joint_velocity_cmd
// stamped with the state's stamp, as the lock-step contract (ehc_sim::StepScheduler) requires.
// Wall-time guards only stop a hung test; no assertion depends on wall time.

#include "ehc_control/pose_math.h"
#include "ehc_msgs/JointVelocityCommand.h"
#include "ehc_msgs/SimStatus.h"

#include <geometry_msgs/Twist.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/JointState.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

namespace ehc_sim::test {

struct State {
  ros::Time stamp;
  std::vector<double> q, qd;
  double x = 0, y = 0, yaw = 0;
};

class LockStepController {
 public:
  /// Fills the commands answering state number k (base zero, arm six zero rates by default;
  /// the policy may also resize the arm command to test a malformed one).
  using Policy = std::function<void(int k, const State& s, geometry_msgs::Twist* base, std::vector<double>* arm)>;

  LockStepController() {
    ros::NodeHandle nh;
    const auto fast = ros::TransportHints().tcpNoDelay();
    js_sub_ = nh.subscribe("/joint_states", 100, &LockStepController::onJs, this, fast);
    odom_sub_ = nh.subscribe("/odom", 100, &LockStepController::onOdom, this, fast);
    status_sub_ = nh.subscribe("/sim/status", 100, &LockStepController::onStatus, this, fast);
    clock_sub_ = nh.subscribe("/clock", 100, &LockStepController::onClock, this, fast);
    cmd_pub_ = nh.advertise<geometry_msgs::Twist>("/cmd_vel", 10);
    arm_pub_ = nh.advertise<ehc_msgs::JointVelocityCommand>("/arm/joint_velocity_cmd", 10);
  }
  virtual ~LockStepController() = default;

  /// Spins until `done()` or a generous wall-time guard expires (a hang, not a timing check).
  bool spinUntil(const std::function<bool()>& done, double guard_s = 60.0) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(guard_s);
    while (ros::ok() && ros::WallTime::now() < end) {
      ros::spinOnce();
      if (done()) return true;
      ros::WallDuration(0.0002).sleep();
    }
    return false;
  }

  /// Topics connected both ways.
  virtual bool connected() {
    return spinUntil([&] {
      return cmd_pub_.getNumSubscribers() > 0 && arm_pub_.getNumSubscribers() > 0 &&
             js_sub_.getNumPublishers() > 0 && odom_sub_.getNumPublishers() > 0 &&
             status_sub_.getNumPublishers() > 0;
    });
  }

  /// Waits until the state (joint_states + odom + status) stamped `t` is in.
  bool waitState(const ros::Time& t) {
    return spinUntil([&] {
      return js_.stamp == t && odom_stamp_ == t && status_.header.stamp == t;
    });
  }

  /// Answers `n` states with `policy`, returns the states seen (n + 1, the last unanswered).
  std::vector<State> run(int n, const Policy& policy) {
    std::vector<State> out;
    for (int k = 0; k <= n; ++k) {
      if (!spinUntil([&] { return js_.stamp > last_answered_ && odom_stamp_ == js_.stamp &&
                                  status_.header.stamp == js_.stamp; })) {
        ADD_FAILURE() << "no state after " << k << " steps";
        return out;
      }
      State s = js_;
      s.x = odom_.x;
      s.y = odom_.y;
      s.yaw = odom_.yaw;
      out.push_back(s);
      if (k == n) break;
      geometry_msgs::Twist base;
      ehc_msgs::JointVelocityCommand arm;
      arm.header.stamp = s.stamp;
      arm.names = {"joint1", "joint2", "joint3", "joint4", "joint5", "joint6"};
      arm.velocities.assign(6, 0.0);
      policy(k, s, &base, &arm.velocities);
      cmd_pub_.publish(base);
      arm_pub_.publish(arm);
      last_answered_ = s.stamp;
    }
    return out;
  }

  State js_;
  int js_received_ = 0;  ///< /joint_states messages so far (a resent state counts again)
  State odom_;
  ros::Time odom_stamp_;
  ehc_msgs::SimStatus status_;
  ros::Time clock_;

 protected:
  ros::Time last_answered_;

 private:
  void onJs(const sensor_msgs::JointState::ConstPtr& m) {
    js_.stamp = m->header.stamp;
    js_.q = m->position;
    js_.qd = m->velocity;
    ++js_received_;
  }
  void onOdom(const nav_msgs::Odometry::ConstPtr& m) {
    odom_stamp_ = m->header.stamp;
    odom_.x = m->pose.pose.position.x;
    odom_.y = m->pose.pose.position.y;
    const auto& o = m->pose.pose.orientation;
    odom_.yaw = ehc_control::yawFromQuaternion(Eigen::Quaterniond(o.w, o.x, o.y, o.z));
  }
  void onStatus(const ehc_msgs::SimStatus::ConstPtr& m) { status_ = *m; }
  void onClock(const rosgraph_msgs::Clock::ConstPtr& m) { clock_ = m->clock; }

  ros::Subscriber js_sub_, odom_sub_, status_sub_, clock_sub_;
  ros::Publisher cmd_pub_, arm_pub_;
};

}  // namespace ehc_sim::test
