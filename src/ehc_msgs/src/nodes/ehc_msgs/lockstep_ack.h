#pragma once
// LockstepAck: a node's part in a lock-step simulator's acknowledgement gate (ehc_sim_node
// _lockstep_acks, ehc_sim::StepScheduler::setAckGate; demo.sh). The convention lives here, beside
// the messages, because nodes of several packages take part (tag, grasp and obstacle nodes,
// the grasp sequencer). With the private parameter _ack_topic:=<topic> (demo.sh:
// /sim/lockstep_ack) the node publishes std_msgs/Header messages with its name as frame_id:
//   - "ready" (stamp 0) every 0.2 wall s until its first frame, once every input topic it names
//     has a publisher connected: the simulator publishes its first state only when every node
//     of its gate is ready, so no node misses the start (which made runs differ);
//   - done(stamp) for every frame (image, cloud or state) it is done with, whatever came of it,
//     after what it made of the frame is published: the simulator steps on only then.
// Without _ack_topic it does nothing. Header-only (roscpp, std_msgs).

#include <ros/names.h>
#include <ros/ros.h>
#include <ros/topic_manager.h>
#include <std_msgs/Header.h>

#include <string>
#include <vector>

namespace ehc_msgs {

class LockstepAck {
 public:
  /// `inputs`: the topics the node must be connected to before it is ready (as the node
  /// subscribes them: relative names and remappings are resolved), e.g. its sensor topic and /tf.
  LockstepAck(const ros::NodeHandle& pnh, const std::vector<std::string>& inputs) {
    pnh.param<std::string>("ack_topic", topic_, "");
    if (topic_.empty()) return;
    ros::NodeHandle nh;
    pub_ = nh.advertise<std_msgs::Header>(topic_, 50);
    for (const auto& t : inputs) inputs_.push_back(ros::names::resolve(t));
    ready_timer_ = nh.createWallTimer(ros::WallDuration(0.2), [this](const ros::WallTimerEvent&) { announce(); });
  }

  /// "" when off, else the topic (for the start-up summary).
  const std::string& topic() const { return topic_; }

  /// Done with the frame stamped `stamp`.
  void done(const ros::Time& stamp) {
    if (!pub_) return;
    if (!started_) {
      started_ = true;
      ready_timer_.stop();
    }
    publish(stamp);
  }

 private:
  void announce() {
    if (started_) return;
    std::string missing;
    for (const auto& t : inputs_)
      if (ros::TopicManager::instance()->getNumPublishers(t) == 0) missing += " " + t;
    if (!missing.empty()) {
      ROS_INFO_STREAM_THROTTLE(5.0, "[LockstepAck] not ready for the lock-step yet: no publisher on" << missing);
      return;
    }
    publish(ros::Time(0));
  }

  void publish(const ros::Time& stamp) const {
    std_msgs::Header h;
    h.stamp = stamp;
    h.frame_id = ros::this_node::getName();
    pub_.publish(h);
  }

  std::string topic_;
  ros::Publisher pub_;
  std::vector<std::string> inputs_;
  ros::WallTimer ready_timer_;
  bool started_ = false;
};

}  // namespace ehc_msgs
