// ehc_controller_node: ROS wrapper of ehc_control::ControlCycle (control_cycle.h: watchdog, TfM,
// sig(omega), proportional or PBVS/MPBS servo, EHC QP).
//   rosrun ehc_control ehc_controller_node _config:=config/control/controller.yaml [_robot:=robot.yaml]
//       [_mode:=ehc|ehc_place|neo_e|neo_c|tsmm] [_servo:=pbvs|proportional] [_mpbs:=true|false] [_target_timeout:=<s>]
//       [_require_obstacles:=false] [_trigger:=state|timer]   (private parameters: ehc_common::initNode, docs/NODES.md)
// Subscribes /joint_states, /odom, /ehc/target_pose (PoseStamped, world frame: the TCP goal),
// /ehc/obstacles, /ehc/target_centre (PointStamped, world frame: the point the camera watches when
// it is not the goal's, e.g. the object behind a pre-grasp goal). Publishes /cmd_vel,
// /arm/joint_velocity_cmd (stamp = joint state stamp), /ehc/status. One cycle per joint state once
// odometry of the same stamp is in (node.trigger: state, lock-step sim) or on a timer (real robot).
// Every input's age is its RECEIPT time on this node's ROS clock (a sender's clock offset cannot
// stretch a timeout; header stamps only pair joint state and odometry in lock-step and stamp
// the answers). Watchdogs, so zeros go out even when no cycle runs (ehc_control::CycleWatchdog
// decides, the node's timers ask it):
//   - lock-step: a ROS-time timer publishes zeros (STOPPED) when no cycle ran for
//     watchdog.state_timeout (state lost while /clock runs);
//   - every mode: a wall-clock timer publishes zeros when no cycle ran for node.wall_timeout
//     wall seconds while ROS time stood still as long (a dead simulator stops /clock as well).
// In timer mode the timer cycle itself stops within the timeout + one cycle period.
// Lock-step (trigger state): an obstacle list is taken by the first cycle answering a state
// stamped after it (an obstacle node computes the list of state t while this node answers t;
// which of the two finished first must not decide the command), with its receipt time.

#include "ehc_msgs/ControllerStatus.h"
#include "ehc_msgs/JointVelocityCommand.h"
#include "ehc_msgs/ObstacleArray.h"
#include "ehc_common/logging.h"
#include "ehc_common/lockstep_ack.h"
#include "ehc_common/node_init.h"
#include "ehc_common/config_node.h"
#include "ehc_control/control_cycle.h"
#include "ehc_control/controller_node_config.h"
#include "ehc_control/pose_math.h"

#include <geometry_msgs/PointStamped.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>

#include <deque>

using ehc_common::ConfigNode;

namespace {

using namespace ehc_control;

using ehc_common::kLogThrottle;

/// controller.yaml with the node's private overrides applied.
ControlCycleParams loadParams(const ConfigNode& cfg, const ehc_common::NodeParams& params) {
  ControlCycleParams p = loadControlCycleParams(cfg);
  p.robot_file = params.getParsed<std::string>("robot", resolveRobotFile).value_or(p.robot_file);  // name or path
  p.controller.mode = params.getParsed<ControlMode>("mode", controlModeFromString).value_or(p.controller.mode);
  p.servo_type = params.getParsed<ServoType>("servo", servoTypeFromString).value_or(p.servo_type);
  p.mpbs.enabled = params.get("mpbs", p.mpbs.enabled);
  p.watchdog.target_timeout = params.get("target_timeout", p.watchdog.target_timeout);
  p.watchdog.require_obstacles = params.get("require_obstacles", p.watchdog.require_obstacles);
  params.validate([&] { p.validate(); });
  return p;
}

/// controller.yaml's node: section with the _trigger override (run_realman.sh: timer, the real
/// robot has no lock-step simulator).
ControllerNodeParams loadNodeParams(const ConfigNode& cfg, const ehc_common::NodeParams& params) {
  ControllerNodeParams p = loadControllerNodeParams(cfg);
  p.trigger = params.getParsed<CycleTrigger>("trigger", cycleTriggerFromString).value_or(p.trigger);
  return p;
}

template <class XYZ>
Eigen::Vector3d toEigen(const XYZ& p) { return Eigen::Vector3d(p.x, p.y, p.z); }
Eigen::Quaterniond toEigen(const geometry_msgs::Quaternion& q) { return Eigen::Quaterniond(q.w, q.x, q.y, q.z); }

class ControllerNode {
 public:
  ControllerNode(ros::NodeHandle& nh, const ehc_common::NodeParams& params, const ConfigNode& cfg)
      : cycle_(loadParams(cfg, params)), node_(loadNodeParams(cfg, params)),
        watchdog_(cycle_.params().watchdog.state_timeout, node_.wall_timeout),
        world_frame_(cycle_.model().config().world_frame) {
    ROS_INFO_STREAM("ehc_controller_node\n" << cycle_.summary() << "\n  " << node_.summary());
    if (!cycle_.params().watchdog.require_obstacles)
      ROS_WARN_STREAM("[ehc_controller_node] obstacle sensing is OFF (watchdog.require_obstacles false): the robot "
                      "moves without obstacle dampers whenever no fresh /ehc/obstacles list is in; every /ehc/status "
                      "says obstacles_required: false");
    // After the solve the watchdog is checked again on the ROS clock (ControlCycle::update).
    cycle_.setClock([] { return ros::Time::now().toSec(); });
    cmd_vel_ = nh.advertise<geometry_msgs::Twist>("cmd_vel", 1);
    arm_cmd_ = nh.advertise<ehc_msgs::JointVelocityCommand>("arm/joint_velocity_cmd", 1);
    status_ = nh.advertise<ehc_msgs::ControllerStatus>("ehc/status", 10);
    subs_.push_back(nh.subscribe("joint_states", 10, &ControllerNode::onJoints, this, ros::TransportHints().tcpNoDelay()));
    subs_.push_back(nh.subscribe("odom", 10, &ControllerNode::onOdom, this, ros::TransportHints().tcpNoDelay()));
    // Lock-step: the target and the obstacle list for a state were published before the
    // acknowledgements that let the simulator publish it, but on other connections; they are
    // taken when the state comes, after one receive pass (tryCycle), on their own queue.
    ros::NodeHandle inputs_nh(nh);
    if (node_.trigger == CycleTrigger::State) inputs_nh.setCallbackQueue(&inputs_queue_);
    subs_.push_back(inputs_nh.subscribe("ehc/target_pose", 10, &ControllerNode::onTarget, this, ros::TransportHints().tcpNoDelay()));
    subs_.push_back(inputs_nh.subscribe("ehc/target_centre", 10, &ControllerNode::onTargetCentre, this, ros::TransportHints().tcpNoDelay()));
    subs_.push_back(inputs_nh.subscribe("ehc/obstacles", 10, &ControllerNode::onObstacles, this, ros::TransportHints().tcpNoDelay()));
    const double state_timeout = cycle_.params().watchdog.state_timeout;
    if (node_.trigger == CycleTrigger::Timer)
      timer_ = nh.createTimer(ros::Duration(1.0 / node_.rate), [this](const ros::TimerEvent&) { cycle(ros::Time::now()); });
    else  // lock-step: no state, no cycle; this timer (ROS time) stops the robot instead
      timer_ = nh.createTimer(ros::Duration(state_timeout / 10.0), [this](const ros::TimerEvent&) {
        const ros::Time now = ros::Time::now();
        const std::string why = watchdog_.checkRosTime(now.toSec());
        if (!why.empty()) publish(cycle_.stopped(now.toSec(), why), now, false);
      });
    wall_timer_ = nh.createWallTimer(ros::WallDuration(node_.wall_timeout / 10.0), [this](const ros::WallTimerEvent&) {
      const ros::Time now = ros::Time::now();
      const std::string why = watchdog_.checkWallClock(ros::WallTime::now().toSec(), now.toSec());
      if (!why.empty()) publish(cycle_.stopped(now.toSec(), why), now, false);
    });
  }

 private:
  std::string frameError(const std::string& frame) const {
    return frame.empty() || frame == world_frame_ ? "" : "frame '" + frame + "', expected '" + world_frame_ + "'";
  }

  void onJoints(const sensor_msgs::JointState& m) {
    const std::string err = cycle_.setJointState(ros::Time::now().toSec(), m.name, m.position);  // receipt time
    if (!err.empty()) ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "[ehc_controller_node] rejected /joint_states: " << err);
    if (node_.trigger == CycleTrigger::State) {
      pending_ = m.header.stamp;
      tryCycle();
    }
  }
  void onOdom(const nav_msgs::Odometry& m) {
    const auto& p = m.pose.pose;
    // A non-unit (e.g. all-zero) quaternion gives a NaN yaw, which the cycle rejects.
    const double yaw = yawFromQuaternion(toEigen(p.orientation));
    const std::string err = cycle_.setBasePose(ros::Time::now().toSec(), Eigen::Vector3d(p.position.x, p.position.y, yaw));  // receipt time
    if (!err.empty()) ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "[ehc_controller_node] rejected /odom: " << err);
    odom_stamp_ = m.header.stamp;
    if (node_.trigger == CycleTrigger::State) tryCycle();
  }
  void onTarget(const geometry_msgs::PoseStamped& m) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = toEigen(m.pose.position);
    T.linear() = rotationFromQuaternion(toEigen(m.pose.orientation));  // NaN (rejected) unless a rotation
    // Receipt time (ROS time): a target is fresh while it keeps arriving.
    std::string err = frameError(m.header.frame_id);
    if (err.empty()) err = cycle_.setTarget(ros::Time::now().toSec(), T);
    if (!err.empty()) ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "[ehc_controller_node] rejected /ehc/target_pose: " << err);
  }
  void onTargetCentre(const geometry_msgs::PointStamped& m) {
    std::string err = frameError(m.header.frame_id);
    if (err.empty()) err = cycle_.setWatchedCentre(ros::Time::now().toSec(), toEigen(m.point));
    if (!err.empty()) ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "[ehc_controller_node] rejected /ehc/target_centre: " << err);
  }
  void onObstacles(const ehc_msgs::ObstacleArray& m) {
    std::vector<ObstaclePair> pairs;
    for (const auto& o : m.obstacles)
      pairs.push_back({o.link, toEigen(o.link_point), toEigen(o.obstacle_point), toEigen(o.normal), o.distance});
    if (node_.trigger == CycleTrigger::State) {
      // A stamp older than the last one kept: the clock jumped back (simulator reset).
      if (!pending_obstacles_.empty() && m.header.stamp < pending_obstacles_.back().stamp) pending_obstacles_.clear();
      if (pending_obstacles_.size() >= kMaxPendingObstacles) pending_obstacles_.pop_front();
      pending_obstacles_.push_back({m.header.stamp, ros::Time::now(), std::move(pairs)});
      return;
    }
    applyObstacles(ros::Time::now(), pairs);
  }
  void applyObstacles(const ros::Time& receipt, const std::vector<ObstaclePair>& pairs) {
    const std::string err = cycle_.setObstacles(receipt.toSec(), pairs);
    if (!err.empty()) ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "[ehc_controller_node] rejected /ehc/obstacles: " << err);
  }
  /// Lock-step: the newest obstacle list stamped before the state stamped `stamp` (older ones
  /// are superseded by it).
  void applyObstaclesBefore(const ros::Time& stamp) {
    const PendingObstacles* newest = nullptr;
    std::size_t used = 0;
    for (const auto& p : pending_obstacles_) {
      if (!(p.stamp < stamp)) break;
      newest = &p;
      ++used;
    }
    if (newest) applyObstacles(newest->receipt, newest->pairs);
    pending_obstacles_.erase(pending_obstacles_.begin(), pending_obstacles_.begin() + static_cast<long>(used));
  }

  /// Lock-step: answer the joint state once odometry of the same instant has arrived.
  void tryCycle() {
    if (pending_.isZero() || odom_stamp_ != pending_) return;
    const ros::Time stamp = pending_;
    pending_ = ros::Time();
    // Everything that reached this process before the state is queued after one receive pass
    // (roscpp keeps the order per connection only): the sequencer's goal for the previous
    // status is then used in this cycle, whatever the CPU load.
    if (!poll_pass_.wait(ehc_common::kLockstepWallWait))
      ROS_WARN_STREAM_THROTTLE(kLogThrottle, "[ehc_controller_node] roscpp's receive thread did not pass within "
                                                 << ehc_common::kLockstepWallWait << " wall s");
    inputs_queue_.callAvailable();
    applyObstaclesBefore(stamp);
    cycle(stamp);
  }

  void cycle(const ros::Time& stamp) {
    const double now = ros::Time::now().toSec();
    watchdog_.cycleRan(now, ros::WallTime::now().toSec());
    answered_ = stamp;
    publish(cycle_.update(now), stamp, true);
  }

  /// Publishes one cycle's (or a watchdog's) command and status. `stamp`: the joint state
  /// answered (lock-step) or the cycle time; a watchdog's arm command carries the last answered
  /// stamp (a lock-step simulator takes it for stale, not for an answer to a newer state).
  void publish(const ControlCycleOutput& out, const ros::Time& stamp, bool from_cycle) {
    const ControlCycleStatus& s = out.status;
    if (!from_cycle)
      ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "[ehc_controller_node] watchdog: " << s.reason << " -> zero command");
    if (!out.event.empty()) ROS_INFO_STREAM("[ehc_controller_node] " << out.event);
    if (s.controller_error)
      ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "[ehc_controller_node] " << s.reason << " -> zero command");
    else if (s.phase == ControlPhase::QpFailed)
      ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "[ehc_controller_node] QP_FAILED: " << s.reason << " -> zero command");
    else if (from_cycle && (s.phase == ControlPhase::Stopped || s.phase == ControlPhase::TargetLost ||
                            s.phase == ControlPhase::ObstaclesStale))
      ROS_WARN_STREAM_THROTTLE(kLogThrottle, "[ehc_controller_node] " << s.phase << ": " << s.reason << " -> zero command");

    ehc_msgs::ControllerStatus st;
    st.header.stamp = stamp;
    st.header.frame_id = world_frame_;
    st.phase = toString(s.phase);
    st.reason = s.reason;
    st.mode = toString(s.mode);
    st.position_error = s.position_error;
    st.orientation_error = s.orientation_error;
    st.error_norm = s.error_norm;
    st.omega = s.omega;
    st.sig_omega = s.sig;
    st.base_weight = s.base_weight;
    st.target_in_fov = s.target_in_fov;
    st.tfm = s.tfm;
    st.qp_status = toString(s.qp_status);
    st.solve_time_us = s.solve_time_us;
    st.obstacle_rows = static_cast<uint32_t>(s.obstacle_rows);
    st.target_age = s.target_age;
    st.state_age = s.state_age;
    st.obstacles_age = s.obstacles_age;
    st.obstacles_required = s.obstacles_required;
    st.motion_limit = toString(s.motion_limit.limit);
    st.motion_limit_joint = s.motion_limit.joint;
    st.motion_limit_link = s.motion_limit.link;
    st.motion_limit_obstacle_point.x = s.motion_limit.obstacle_point.x();
    st.motion_limit_obstacle_point.y = s.motion_limit.obstacle_point.y();
    st.motion_limit_obstacle_point.z = s.motion_limit.obstacle_point.z();
    st.motion_limit_value = s.motion_limit.value;
    st.motion_limit_detail = s.motion_limit.detail();

    const Eigen::VectorXd& v = out.velocity;
    const int nb = cycle_.model().nBase();
    geometry_msgs::Twist tw;
    tw.linear.x = v[0];
    if (nb == 3) tw.linear.y = v[1];
    tw.angular.z = v[nb - 1];
    ehc_msgs::JointVelocityCommand ac;
    ac.header.stamp = from_cycle ? stamp : answered_;
    ac.names = cycle_.model().config().arm_joints;
    ac.velocities.assign(v.data() + nb, v.data() + v.size());
    cmd_vel_.publish(tw);
    arm_cmd_.publish(ac);
    status_.publish(st);
  }

  ControlCycle cycle_;
  ControllerNodeParams node_;
  CycleWatchdog watchdog_;  ///< decides the two watchdog timers
  std::string world_frame_;
  ros::Publisher cmd_vel_, arm_cmd_, status_;
  /// Lock-step: target, target centre, obstacles (taken per state). Declared before the
  /// subscribers that use it, so it outlives them (destroyed first, their shutdown would lock
  /// its destroyed mutex: an abort when start-up fails after they were made).
  ros::CallbackQueue inputs_queue_;
  std::vector<ros::Subscriber> subs_;
  ros::Timer timer_;            ///< timer trigger: the cycle; lock-step: the ROS-time watchdog
  ros::WallTimer wall_timer_;   ///< wall-clock watchdog (every mode)
  ros::Time pending_, odom_stamp_;
  struct PendingObstacles {
    ros::Time stamp, receipt;
    std::vector<ObstaclePair> pairs;
  };
  std::deque<PendingObstacles> pending_obstacles_;  ///< lock-step: lists by arrival, not yet taken
  static constexpr std::size_t kMaxPendingObstacles = 100;  ///< no state for long: the oldest go
  ros::Time answered_;  ///< the stamp the last cycle answered
  ehc_common::PollPassBarrier poll_pass_;
};

}  // namespace

int main(int argc, char** argv) {
  return ehc_common::runNode(argc, argv, "ehc_controller_node", 1, [](const ehc_common::NodeParams& params, ros::NodeHandle& nh) {
    const ConfigNode cfg = ConfigNode::loadFile(params.requireText("config", "<controller.yaml>"), "ControllerNode");
    ControllerNode node(nh, params, cfg);
    cfg.rejectUnknownKeys();  // every loader has run: a key none of them read is a misspelling
    ehc_common::checkNodeParams(params);
    ros::spin();
    return 0;
  });
}
