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

#include "ehc_common/logging.h"
#include "ehc_common/node_params.h"

#include <ros/names.h>
#include <ros/poll_manager.h>
#include <ros/ros.h>
#include <ros/topic_manager.h>
#include <std_msgs/Header.h>

#include <tf2_ros/buffer.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace ehc_common {

class LockstepAck {
 public:
  /// `inputs`: the topics the node must be connected to before it is ready (as the node
  /// subscribes them: relative names and remappings are resolved), e.g. its sensor topic and /tf.
  LockstepAck(const NodeParams& params, const std::vector<std::string>& inputs) {
    topic_ = params.get<std::string>("ack_topic", "");
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
      ROS_INFO_STREAM_THROTTLE(kLogThrottle, "[LockstepAck] not ready for the lock-step yet: no publisher on" << missing);
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

/// Inputs a lock-step node takes by their stamps, not by when they arrived: each is held with
/// its stamp and a source number (which orders inputs of one stamp) until takeBefore(t) hands
/// over, oldest first, every input stamped before t. An input whose take() returns false (not
/// ready, e.g. its tf has not arrived) stays until it is more than `max_wait` s of stamps old, then goes.
/// A t older than the last one (the clock jumped back: simulator reset) drops everything held.
class StampedInbox {
 public:
  void add(const ros::Time& stamp, int source, std::function<bool()> take) {
    held_.emplace(std::make_pair(stamp, source), std::move(take));
  }
  void takeBefore(const ros::Time& t, double max_wait = 0.0) {
    if (!last_.isZero() && t < last_) held_.clear();
    last_ = t;
    for (auto it = held_.begin(); it != held_.end() && it->first.first < t;) {
      if (it->second() || (t - it->first.first).toSec() > max_wait) it = held_.erase(it);
      else ++it;
    }
  }
  /// The stamp of the last takeBefore (zero before the first).
  const ros::Time& last() const { return last_; }

 private:
  std::multimap<std::pair<ros::Time, int>, std::function<bool()>> held_;
  ros::Time last_;
};

/// Lock-step receipt order across connections. roscpp keeps the order of messages per connection
/// only: a message published before a trigger on another connection (the sequencer's target
/// before its acknowledgement, which lets the simulator publish the next cloud) has reached this
/// process first, but roscpp's poll thread may read both sockets in one pass and queue the
/// trigger first. wait() returns once the poll thread has finished a pass begun after the call
/// (it is woken at once): every message that reached this process before the trigger is then in
/// its callback queue. Call it in the trigger's callback, then run the other inputs' queue.
class PollPassBarrier {
 public:
  PollPassBarrier() {
    connection_ = ros::PollManager::instance()->addPollThreadListener([this] {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        ++passes_;
      }
      passed_.notify_all();
    });
  }
  ~PollPassBarrier() { ros::PollManager::instance()->removePollThreadListener(connection_); }
  PollPassBarrier(const PollPassBarrier&) = delete;
  PollPassBarrier& operator=(const PollPassBarrier&) = delete;

  /// False if the poll thread did not finish a pass within `wall_s` (shutting down).
  bool wait(double wall_s) {
    std::unique_lock<std::mutex> lock(mutex_);
    const std::uint64_t next = passes_ + 1;  // the listener runs at the start of each pass
    lock.unlock();
    ros::PollManager::instance()->getPollSet().signal();  // wakes a poll() that waits for data
    lock.lock();
    return passed_.wait_for(lock, std::chrono::duration<double>(wall_s), [&] { return passes_ >= next; });
  }

 private:
  boost::signals2::connection connection_;
  std::mutex mutex_;
  std::condition_variable passed_;
  std::uint64_t passes_ = 0;
};

/// Lock-step: wall s a node waits for a frame's camera pose (or one receive pass) before it drops
/// the frame with a logged reason; far more than a loaded machine needs, far less than a hang.
constexpr double kLockstepWallWait = 1.0;

/// Waits on the wall clock (at most `wall_s`) until `buffer` can transform `source` into
/// `target` at `stamp`. In lock-step a pose of the current stamp came with the state, but the
/// tf listener's thread may lag under CPU load; a tf2 lookup with a timeout would wait on sim
/// time, which stands still until this node is done (a deadlock).
inline bool waitForTransformWall(const tf2_ros::Buffer& buffer, const std::string& target, const std::string& source,
                                 const ros::Time& stamp, double wall_s) {
  const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(wall_s);
  while (!buffer.canTransform(target, source, stamp)) {
    if (ros::WallTime::now() > give_up || !ros::ok()) return false;
    ros::WallDuration(0.001).sleep();
  }
  return true;
}

}  // namespace ehc_common
