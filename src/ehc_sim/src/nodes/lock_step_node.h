#pragma once
// The ROS side of the lock-step contract, shared by both simulator nodes (ehc_sim_node,
// ehc_kinematic_sim_node): the _free_run / _seed overrides, the command subscriptions (with
// logged rejections) and the loop that serves callbacks and does what ehc_sim::StepScheduler
// decides. Header-only; the policy itself is the core's StepScheduler.

#include "ehc_msgs/JointVelocityCommand.h"
#include "ehc_common/logging.h"
#include "ehc_common/node_params.h"
#include "ehc_sim/step_scheduler.h"

#include <geometry_msgs/Twist.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>

#include <functional>
#include <stdexcept>
#include <string>

namespace ehc_sim {

using ehc_common::kLogThrottle;

/// Private parameters _robot (a robot name or a robot.yaml), _free_run and _seed override the
/// configuration file.
inline void applyNodeOverrides(const ehc_common::NodeParams& params, FakeRobotConfig* cfg) {
  cfg->robot_file = params.getParsed<std::string>("robot", ehc_control::resolveRobotFile).value_or(cfg->robot_file);
  cfg->free_run = params.get("free_run", cfg->free_run);
  cfg->seed = params.get<unsigned>("seed", cfg->seed);
}

class LockStepNode {
 public:
  /// `node` names the node in log messages. Everything `nh` serves runs on queue(), from run().
  LockStepNode(ros::NodeHandle& nh, const std::string& node, const ehc_control::RobotConfig& robot,
               const FakeRobotConfig& config)
      : node_(node), scheduler_(robot, config) {
    nh.setCallbackQueue(&queue_);
    const ros::TransportHints fast = ros::TransportHints().tcpNoDelay();
    cmd_vel_sub_ = nh.subscribe("/cmd_vel", 10, &LockStepNode::onCmdVel, this, fast);
    arm_sub_ = nh.subscribe("/arm/joint_velocity_cmd", 10, &LockStepNode::onArmCommand, this, fast);
  }

  /// To call by the node's publishState just before /joint_states (the message answered).
  void statePublished(const ros::Time& stamp, bool fresh) {
    scheduler_.statePublished(ros::WallTime::now().toSec(), static_cast<std::int64_t>(stamp.toNSec()), fresh);
  }

  /// With an acknowledgement gate: serves callbacks until every node of the gate is ready and
  /// the controller's command publishers are connected (its first answer is not lost), logging
  /// who it waits for every 5 s; false on shutdown. At once without a gate.
  bool waitForAckGate() {
    if (scheduler_.notJoined().empty()) return true;  // no gate
    const double t0 = ros::WallTime::now().toSec();
    double last_log = t0;
    while (ros::ok()) {
      std::string missing = scheduler_.notJoined();
      if (cmd_vel_sub_.getNumPublishers() == 0 || arm_sub_.getNumPublishers() == 0)
        missing += (missing.empty() ? "" : " ") + std::string("the controller (/cmd_vel, /arm/joint_velocity_cmd)");
      if (missing.empty()) {
        ROS_INFO_STREAM("[" << node_ << "] lock-step: every node of the acknowledgement gate and the controller are there after "
                            << ros::WallTime::now().toSec() - t0 << " wall s: first state");
        return true;
      }
      queue_.callAvailable(ros::WallDuration(0.05));
      const double wall = ros::WallTime::now().toSec();
      if (wall - last_log > 5.0) {
        last_log = wall;
        ROS_WARN_STREAM("[" << node_ << "] lock-step: the first state waits " << wall - t0
                            << " wall s for the acknowledgement gate's nodes: " << missing);
      }
    }
    return false;
  }

  /// Serves callbacks until shutdown; `step()` on StepAction::Step (it executes command() and
  /// publishes the fresh state), `republish()` on StepAction::RepublishState.
  void run(const std::function<void()>& step, const std::function<void()>& republish) {
    double last_step = ros::WallTime::now().toSec();
    while (ros::ok()) {
      queue_.callAvailable(ros::WallDuration(scheduler_.callbackWait()));
      const double wall = ros::WallTime::now().toSec();
      switch (scheduler_.next(wall)) {
        case StepAction::Step:
          step();
          last_step = wall;
          break;
        case StepAction::RepublishState: republish(); break;  // nobody answered
        case StepAction::Wait:
          if (wall - last_step > 2.0) {
            const std::string who = scheduler_.ackWait();
            if (!who.empty())
              ROS_WARN_STREAM_THROTTLE(kLogThrottle, "[" << node_ << "] lock-step: sim time waits " << wall - last_step
                                                << " wall s for an acknowledgement: " << who);
          }
          break;
      }
    }
  }

  StepScheduler& scheduler() { return scheduler_; }

 private:
  void onCmdVel(const geometry_msgs::Twist::ConstPtr& m) {
    const std::string why = scheduler_.onBaseTwist(ros::WallTime::now().toSec(), m->linear.x, m->linear.y, m->angular.z);
    if (!why.empty())
      ROS_WARN_STREAM_THROTTLE(kLogThrottle, "[" << node_ << "] /cmd_vel rejected (base stopped): " << why << " ("
                                                 << scheduler_.counters().base_rejected << " rejected so far)");
  }

  void onArmCommand(const ehc_msgs::JointVelocityCommand::ConstPtr& m) {
    const std::string why = scheduler_.onArmCommand(
        ros::WallTime::now().toSec(), static_cast<std::int64_t>(m->header.stamp.toNSec()), m->names, m->velocities);
    if (!why.empty())
      ROS_WARN_STREAM_THROTTLE(kLogThrottle, "[" << node_ << "] /arm/joint_velocity_cmd rejected: " << why << " ("
                                                 << scheduler_.counters().arm_rejected << " rejected, "
                                                 << scheduler_.counters().arm_stale << " stale so far)");
  }

  std::string node_;
  ros::CallbackQueue queue_;
  StepScheduler scheduler_;
  ros::Subscriber cmd_vel_sub_, arm_sub_;
};

}  // namespace ehc_sim
