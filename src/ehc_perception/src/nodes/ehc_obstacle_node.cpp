// ehc_obstacle_node: depth clouds -> OctoMap; robot state -> FCL link-obstacle distances on
// /ehc/obstacles (ehc_msgs/ObstacleArray) for the controller's velocity dampers. The logic
// (state parsing and freshness, insert rate, exclusion expiry, what to publish) is
// ehc_perception::ObstacleMonitor; this node loads parameters, converts messages (clouds, tf),
// runs the timer and publishes.
//   rosrun ehc_perception ehc_obstacle_node _config:=config/perception/obstacle_node.yaml
// Its parameters: ehc_perception::ObstacleNodeConfig (node_config.h).
// Clouds (at most max_insert_rate_hz; the subscription keeps only the newest in timer mode, and
// a cloud that waited longer than stale_after in the node is dropped) are read within the point
// budget (max_input_points, PointBudget: the points beyond it are never converted), transformed
// into the world frame with tf2 at their stamp, bounded (one point per cloud_voxel voxel, then
// at most max_cloud_points: the work per cloud does not grow with the camera's resolution) and
// queued with the robot's pose, replacing an unfinished one; each
// timer cycle ray-casts points_per_update of them from the sensor origin (no cycle stalls on a
// whole cloud, so the distances keep publish_rate_hz), the robot's own points removed. A timer publishes the distances of every link closer than the
// influence distance while the state (/joint_states + /odom) is fresh (judged by receipt time on
// this node's clock, not by header stamps); with a stale state
// nothing is published and an error is logged (the controller's watchdog then stops).
// Exclusion spheres (ehc_msgs/ObstacleExclusion on exclusion_topic, e.g. the object being
// grasped, sent by the grasp sequencer) are ignored by the distance queries while the list is
// younger than exclusion_timeout; an older list is dropped (the object is an obstacle again).
// Lock-step (_ack_topic:=<topic>, demo.sh; ehc_common::LockstepAck): no timer; each state (the
// /joint_states + /odom pair of one stamp t) first takes the clouds and exclusion lists stamped
// before t (in stamp order, whenever they arrived), then publishes the distances at t when due
// (publish_rate_hz on the stamps; ehc_perception::ObstacleLockstepCycle), then acknowledges t;
// times are the stamps. So the distances do not depend on when messages arrive, and the
// simulator steps on only once they are out.
// What became of the clouds (processed, over the budget, rate-limited, stale, superseded, no
// camera pose, malformed, failed: ehc_perception::FrameCounts) is logged at most every 10 s
// while clouds are dropped (and at the first cloud over the point budget).
#include "ehc_msgs/ObstacleArray.h"
#include "ehc_msgs/ObstacleExclusion.h"
#include "ehc_common/logging.h"
#include "ehc_common/lockstep_ack.h"
#include "ehc_control/robot_config.h"
#include "ehc_control/pose_math.h"
#include "ehc_perception/frame_counts.h"
#include "ehc_perception/node_config.h"
#include "ehc_perception/obstacle_monitor.h"
#include "ros_conversions.h"

#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <tf2_ros/transform_listener.h>

#include <cmath>
#include <functional>
#include <memory>
#include <optional>

namespace {

using namespace ehc_perception;

using ehc_common::kLogThrottle;

class ObstacleNode {
 public:
  ObstacleNode(ros::NodeHandle& nh, const ros::NodeHandle& pnh, const ObstacleNodeConfig& cfg)
      : cfg_(cfg),
        monitor_(ehc_control::loadRobotConfig(cfg.robot_config), cfg.map, cfg.monitor),
        listener_(tf_),
        ack_(pnh, cfg.lockstepInputs()),
        cycle_(cfg.publish_rate_hz) {
    ROS_INFO_STREAM("  " << monitor_.field().summary());
    pub_ = nh.advertise<ehc_msgs::ObstacleArray>(cfg_.output_topic, 5);
    lockstep_ = !ack_.topic().empty();
    // Lock-step: every cloud is kept until its state (the simulator waits for this node).
    const ros::TransportHints fast = ros::TransportHints().tcpNoDelay();  // no Nagle delay (lock-step order)
    cloud_sub_ = nh.subscribe(cfg_.cloud_topic, lockstep_ ? 10 : 1, &ObstacleNode::onCloud, this, fast);
    joints_sub_ = nh.subscribe(cfg_.joint_states_topic, 5, &ObstacleNode::onJoints, this, fast);
    odom_sub_ = nh.subscribe(cfg_.odom_topic, 5, &ObstacleNode::onOdom, this, fast);
    if (!cfg_.exclusion_topic.empty())
      exclusion_sub_ = nh.subscribe(cfg_.exclusion_topic, 5, &ObstacleNode::onExclusion, this, fast);
    if (lockstep_)
      ROS_INFO_STREAM("ehc_obstacle_node: lock-step: distances per state at " << cfg_.publish_rate_hz
                                                                           << " Hz of its stamps, each state acknowledged on " << ack_.topic());
    else
      timer_ = nh.createTimer(ros::Duration(1.0 / cfg_.publish_rate_hz), &ObstacleNode::onTimer, this);
  }

 private:
  /// Freshness is judged by receipt time on this node's clock (ROS time: /clock in lock-step,
  /// the wall clock on the robot), as the controller's watchdogs do, never by header stamps: a
  /// sender's clock offset (another machine, a driver's own clock) must not make a dead state
  /// look fresh or a live one stale.
  /// In lock-step the stamp (the simulator's time, which stands still until this node is done).
  double receiptTime(const ros::Time& stamp) const { return lockstep_ ? stamp.toSec() : ros::Time::now().toSec(); }

  void onJoints(const sensor_msgs::JointState& msg) {
    const std::string why = monitor_.setJointState(receiptTime(msg.header.stamp), msg.name, msg.position);
    if (!why.empty()) ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "ehc_obstacle_node: /joint_states rejected: " << why);
    if (lockstep_) lockstepCycle(cycle_.jointState(static_cast<StampNs>(msg.header.stamp.toNSec())));
  }

  /// Lock-step, a state at t complete (/joint_states and /odom of one stamp): the clouds and
  /// exclusion lists stamped before t, the distances at t (when due), then the acknowledgement
  /// of t.
  void lockstepCycle(const std::optional<ObstacleLockstepCycle::State>& state) {
    if (!state) return;
    ros::Time t;
    t.fromNSec(static_cast<std::uint64_t>(state->stamp));
    inbox_.takeBefore(t, kMaxCloudWait);  // a cloud without its camera pose yet waits for the next state
    if (state->publish) publishDistances(t.toSec());
    ack_.done(t);
  }

  void onOdom(const nav_msgs::Odometry& msg) {
    const auto& p = msg.pose.pose;
    const Eigen::Quaterniond qn(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z);
    const double yaw = ehc_control::yawFromQuaternion(qn);  // NaN unless a unit quaternion
    std::string why = std::isfinite(yaw) ? "" : "orientation is not a unit quaternion";
    if (why.empty()) why = monitor_.setBasePose(receiptTime(msg.header.stamp), Eigen::Vector3d(p.position.x, p.position.y, yaw));
    if (!why.empty()) ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "ehc_obstacle_node: odometry rejected: " << why);
    if (lockstep_) lockstepCycle(cycle_.odometry(static_cast<StampNs>(msg.header.stamp.toNSec())));
  }

  void onExclusion(const ehc_msgs::ObstacleExclusion& msg) {
    if (msg.centres.size() != msg.radii.size()) {
      ROS_ERROR_THROTTLE(kLogThrottle, "ehc_obstacle_node: exclusion list with %zu centres and %zu radii rejected",
                         msg.centres.size(), msg.radii.size());
      return;
    }
    if (!msg.header.frame_id.empty() && msg.header.frame_id != cfg_.world_frame) {
      ROS_ERROR_THROTTLE(kLogThrottle, "ehc_obstacle_node: exclusion list in frame '%s' rejected (expected '%s')",
                         msg.header.frame_id.c_str(), cfg_.world_frame.c_str());
      return;
    }
    std::vector<ExclusionZone> zones;
    for (std::size_t i = 0; i < msg.centres.size(); ++i)
      zones.push_back({Eigen::Vector3d(msg.centres[i].x, msg.centres[i].y, msg.centres[i].z), msg.radii[i]});
    auto apply = [this, zones](double t) {
      const std::string why = monitor_.setExclusionZones(t, zones);
      if (!why.empty()) ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "ehc_obstacle_node: exclusion list rejected: " << why);
    };
    if (lockstep_)
      inbox_.add(msg.header.stamp, kExclusionSource, [apply, t = msg.header.stamp.toSec()] {
        apply(t);
        return true;
      });
    else apply(receiptTime(msg.header.stamp));
  }

  void onCloud(const ros::MessageEvent<const sensor_msgs::PointCloud2>& event) {
    const sensor_msgs::PointCloud2ConstPtr msg = event.getConstMessage();
    if (lockstep_) {
      inbox_.add(msg->header.stamp, kCloudSource, [this, msg] {
        if (!ehc_common::waitForTransformWall(tf_, cfg_.world_frame, msg->header.frame_id, msg->header.stamp, ehc_common::kLockstepWallWait)) {
          ROS_WARN_STREAM_THROTTLE(kLogThrottle, "ehc_obstacle_node: cloud at " << msg->header.stamp << " waits for its camera pose");
          return false;
        }
        insertCloud(*msg);
        return true;
      });
    } else {
      const double waited = (ros::Time::now() - event.getReceiptTime()).toSec();
      if (waited > cfg_.stale_after) {
        ROS_WARN_STREAM_THROTTLE(kLogThrottle, "ehc_obstacle_node: cloud at " << msg->header.stamp << " dropped: it waited "
                                                  << waited << " s in the node (stale_after " << cfg_.stale_after << " s)");
        count(FrameOutcome::Stale);
      } else {
        insertCloud(*msg);
      }
    }
  }

  void count(FrameOutcome o) { ros_conv::countFrame(&counts_, o, "ehc_obstacle_node"); }

  void insertCloud(const sensor_msgs::PointCloud2& msg) {
    const double now = receiptTime(msg.header.stamp);
    if (!monitor_.acceptCloud(now)) return count(FrameOutcome::RateLimited);
    Eigen::Isometry3d T;
    try {
      T = tf2::transformToEigen(tf_.lookupTransform(cfg_.world_frame, msg.header.frame_id, msg.header.stamp,
                                                    ros::Duration(cfg_.tf_timeout)));
    } catch (const tf2::TransformException& e) {
      ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "ehc_obstacle_node: cloud dropped: " << e.what());
      return count(FrameOutcome::NoCameraPose);
    }
    CloudPoints read;
    try {  // the point budget first: the points beyond it are never converted
      read = ros_conv::cloudToPoints(msg, static_cast<std::size_t>(cfg_.monitor.max_input_points));
    } catch (const std::invalid_argument& e) {
      ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "ehc_obstacle_node: cloud dropped: " << e.what());
      return count(FrameOutcome::Malformed);
    }
    try {
      const ObstacleMonitor::CloudInsertion r =
          monitor_.queueCloud(now, transformPoints(read.points, T), T.translation());
      if (!r.self_filtered)
        ROS_WARN_THROTTLE(kLogThrottle, "ehc_obstacle_node: no fresh robot state; cloud inserted without "
                                        "removing the robot's own points");
      if (r.replaced > 0) count(FrameOutcome::Superseded);  // the previous cloud, not all ray-cast
      if (read.read < read.total) counts_.countSubsampled();
      count(FrameOutcome::Processed);
    } catch (const std::exception& e) {
      ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "ehc_obstacle_node: cloud dropped: " << e.what());
      count(FrameOutcome::Failed);
    }
  }

  void onTimer(const ros::TimerEvent&) { publishDistances(ros::Time::now().toSec()); }

  void publishDistances(double now) {
    try {
      const ObstacleReport r = monitor_.update(now);
      if (r.exclusions_expired)
        ROS_WARN("ehc_obstacle_node: exclusion list older than %.2f s dropped: every obstacle counts again",
                 cfg_.monitor.exclusion_timeout);
      if (r.status == ObstacleReport::Status::StateStale) {
        ROS_ERROR_THROTTLE(kLogThrottle, "ehc_obstacle_node: robot state missing or older than %.2f s; "
                                         "no obstacle distances published", cfg_.monitor.state_timeout);
        return;
      }
      ehc_msgs::ObstacleArray out;
      out.header.stamp = ros::Time(r.stamp);
      out.header.frame_id = cfg_.world_frame;
      out.influence_distance = cfg_.map.influence_distance;
      for (const LinkObstacleDistance& d : r.distances) {
        ehc_msgs::ObstacleDistance o;
        o.link = d.link;
        o.link_point.x = d.link_point.x();
        o.link_point.y = d.link_point.y();
        o.link_point.z = d.link_point.z();
        o.obstacle_point.x = d.obstacle_point.x();
        o.obstacle_point.y = d.obstacle_point.y();
        o.obstacle_point.z = d.obstacle_point.z();
        o.normal.x = d.normal.x();
        o.normal.y = d.normal.y();
        o.normal.z = d.normal.z();
        o.distance = d.distance;
        out.obstacles.push_back(o);
      }
      pub_.publish(out);
    } catch (const std::exception& e) {
      ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "ehc_obstacle_node: distances failed: " << e.what());
    }
  }

  ObstacleNodeConfig cfg_;
  ObstacleMonitor monitor_;
  tf2_ros::Buffer tf_;
  tf2_ros::TransformListener listener_;
  ros::Publisher pub_;
  ros::Subscriber cloud_sub_, joints_sub_, odom_sub_, exclusion_sub_;
  ros::Timer timer_;
  ehc_common::LockstepAck ack_;
  bool lockstep_ = false;
  ObstacleLockstepCycle cycle_;  ///< lock-step: when a state is complete and its distances due
  /// Lock-step: clouds and exclusion lists, taken at the first state after their stamp.
  ehc_common::StampedInbox inbox_;
  FrameCounts counts_{"clouds"};  ///< what became of the clouds (logged)
  static constexpr int kExclusionSource = 0, kCloudSource = 1;
  static constexpr double kMaxCloudWait = 1.0;  ///< s of stamps; then the cloud is dropped
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "ehc_obstacle_node");
  ros::NodeHandle nh, pnh("~");
  std::string config;
  if (!pnh.getParam("config", config)) {
    ROS_FATAL("ehc_obstacle_node: missing _config:=<file.yaml> (see config/perception/obstacle_node.yaml)");
    return 2;
  }
  try {
    ObstacleNodeConfig cfg = loadObstacleNodeConfig(config);
    std::string robot;  // _robot:=<name | robot.yaml> overrides node.robot_config
    if (pnh.getParam("robot", robot) && !robot.empty()) cfg.robot_config = ehc_control::resolveRobotFile(robot);
    ROS_INFO_STREAM(cfg.summary());
    ObstacleNode node(nh, pnh, cfg);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("ehc_obstacle_node: " << e.what());
    return 2;
  }
  return 0;
}
