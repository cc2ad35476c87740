#pragma once
// The RealMan adapter nodes' clock (rm_arm_adapter, water2_base_bridge): the steady clock on the
// robot (immune to wall-clock jumps and to the clocks of other machines: every timeout is
// measured on the consuming node's own clock), ROS time under /use_sim_time (a simulator or a
// lock-step test owns /clock, so the nodes' timeouts run on the time it publishes).

#include <ros/ros.h>

#include <chrono>

namespace ehc_realman_nodes {

/// Seconds of the node's clock (see above). ros::Time::isSimTime() is fixed at ros::init.
inline double nodeNow() {
  if (ros::Time::isSimTime()) return ros::Time::now().toSec();
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// A periodic callback on the node's clock: a ros::Timer on ROS time under /use_sim_time (it
/// fires as /clock advances), a steady timer otherwise.
class NodeTimer {
 public:
  NodeTimer() = default;
  template <class F>
  NodeTimer(ros::NodeHandle& nh, double period, F callback) {
    if (ros::Time::isSimTime())
      sim_ = nh.createTimer(ros::Duration(period), [callback](const ros::TimerEvent&) { callback(); });
    else
      steady_ = nh.createSteadyTimer(ros::WallDuration(period),
                                     [callback](const ros::SteadyTimerEvent&) { callback(); });
  }

 private:
  ros::Timer sim_;
  ros::SteadyTimer steady_;
};

}  // namespace ehc_realman_nodes
