// ehc_grasp_node: depth cloud -> grasp candidates on /ehc/grasp_candidates.
//   rosrun ehc_perception ehc_grasp_node _config:=config/perception/grasp_node.yaml
// Its parameters: ehc_perception::GraspNodeConfig (node_config.h).
// The subscription keeps the newest cloud only (one that arrives while the node is busy replaces
// the one waiting); a cloud that waited longer than stale_after in the node is dropped (timer
// mode; in lock-step the simulator waits for the node). Each processed cloud (at most
// max_rate_hz) is read within the point budget (max_input_points, PointBudget: the points
// beyond it are never converted), transformed into the world frame (tf2 at the cloud stamp),
// the support plane removed and the objects clustered; grasps are generated
// for the object nearest the latest /ehc/target_pose (or every object without a fresh
// target) and published best first (ehc_msgs/GraspCandidates, world frame). A cloud
// without a usable grasp publishes an empty candidate list (reason in the log). A cloud waits
// for the camera pose at its stamp on the wall clock (ehc_common::waitForTransformWall: at most
// tf_timeout s, in lock-step ehc_common::kLockstepWallWait s; a lookup with a timeout would wait on lock-step sim
// time, which stands still until this node is done), then is dropped with a logged reason.
// No tf2_ros::MessageFilter: it held a cloud forever when the cloud's transformable request
// was registered just after the transform arrived (tf2::BufferCore::addTransformableRequest
// checks, then registers; a transform inserted in between never answers the request), and in
// lock-step no later transform comes until the cloud is acknowledged: the simulator stalled.
// Time is the clouds' and the target's stamps (the rate limit, the target's age), so which
// cloud is processed with which target does not depend on when messages arrive; the target
// used for a cloud is the newest one stamped before it (ehc_perception::GraspTargetHistory; in
// lock-step every target published before the cloud is taken first, ehc_common::PollPassBarrier;
// one that still comes after the cloud that should have used it is logged). With
// _ack_topic:=<topic> every cloud received is acknowledged there exactly once, whatever came
// of it (processed and its candidates published, skipped by the rate limit, or dropped with a
// logged reason): a lock-step simulator's acknowledgement gate (ehc_common::LockstepAck, demo.sh).
// Targets without tags: the current object's target selector comes on node.selector_topic
// (ehc_msgs/TargetSelector, the sequencer's, latched; taken with the targets). While it is a
// cloud kind (nearest, kth_from_left, kth_from_front) each processed cloud goes through
// generateForCloudTarget (tracked near the latest target, else selected), and the target's pose
// (ehc_control::cloudTargetPose of its cloud centre, stamped with the cloud) is published on
// node.cloud_target_topic for the sequencer; no target: the reason is logged. A new cloud
// selector forgets the targets of the one before (they belong to another object).
// What became of the clouds (processed, over the budget, rate-limited, stale, no camera pose,
// malformed, failed: ehc_perception::FrameCounts) is logged at most every 10 s while clouds are
// dropped (and at the first cloud over the point budget).
#include "ehc_msgs/CloudTarget.h"
#include "ehc_msgs/GraspCandidates.h"
#include "ehc_msgs/TargetSelector.h"
#include "ehc_control/target_selector_msg.h"
#include "ehc_common/logging.h"
#include "ehc_common/lockstep_ack.h"
#include "ehc_common/node_init.h"
#include "ehc_perception/frame_counts.h"
#include "ehc_perception/grasp_generator.h"
#include "ehc_perception/grasp_target_history.h"
#include "ehc_perception/node_config.h"
#include "ehc_perception/rate_limiter.h"
#include "ros_conversions.h"

#include <geometry_msgs/PoseStamped.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <tf2_ros/transform_listener.h>

#include <optional>

namespace {

using namespace ehc_perception;

using ehc_common::kLogThrottle;

class GraspNode {
 public:
  GraspNode(ros::NodeHandle& nh, const ehc_common::NodeParams& params, const GraspNodeConfig& cfg)
      : cfg_(cfg),
        gen_(cfg.generator),
        listener_(tf_),
        limiter_(cfg.targeting.max_rate_hz),
        targets_(cfg.targeting.target_timeout, kMaxTargets),
        ack_(params, cfg.lockstepInputs()) {
    pub_ = nh.advertise<ehc_msgs::GraspCandidates>(cfg_.output_topic, 2);
    lockstep_ = !ack_.topic().empty();
    const ros::TransportHints fast = ros::TransportHints().tcpNoDelay();  // no Nagle delay (lock-step order)
    cloud_sub_ = nh.subscribe(cfg_.cloud_topic, 1, &GraspNode::onCloud, this, fast);  // the newest cloud wins
    if (lockstep_) ROS_INFO_STREAM("ehc_grasp_node: each cloud acknowledged on " << ack_.topic() << " when done");
    if (!cfg_.target_topic.empty()) {  // taken when a cloud comes (onCloud), on their own queue
      ros::SubscribeOptions opts = ros::SubscribeOptions::create<geometry_msgs::PoseStamped>(
          cfg_.target_topic, static_cast<std::uint32_t>(kMaxTargets), [this](const geometry_msgs::PoseStampedConstPtr& m) { onTarget(*m); },
          ros::VoidConstPtr(), &target_queue_);
      opts.transport_hints = fast;
      target_sub_ = nh.subscribe(opts);
    }
    if (!cfg_.selector_topic.empty()) {  // on the targets' queue: taken when a cloud comes
      ros::SubscribeOptions opts = ros::SubscribeOptions::create<ehc_msgs::TargetSelector>(
          cfg_.selector_topic, 5, [this](const ehc_msgs::TargetSelectorConstPtr& m) { onSelector(*m); }, ros::VoidConstPtr(),
          &target_queue_);
      opts.transport_hints = fast;
      selector_sub_ = nh.subscribe(opts);
      cloud_target_pub_ = nh.advertise<ehc_msgs::CloudTarget>(cfg_.cloud_target_topic, 5);
    }
  }

 private:
  void onTarget(const geometry_msgs::PoseStamped& msg) {
    const Eigen::Vector3d p(msg.pose.position.x, msg.pose.position.y, msg.pose.position.z);
    const GraspTargetHistory::Added added = msg.header.frame_id != cfg_.world_frame
                                                ? GraspTargetHistory::Added::Rejected
                                                : targets_.add(stampNs(msg.header.stamp), p);
    if (added == GraspTargetHistory::Added::Rejected)
      ROS_ERROR_THROTTLE(kLogThrottle, "ehc_grasp_node: target ignored (non-finite or frame '%s' != '%s')",
                         msg.header.frame_id.c_str(), cfg_.world_frame.c_str());
    else if (added == GraspTargetHistory::Added::Late)
      ROS_WARN_STREAM_THROTTLE(kLogThrottle, "ehc_grasp_node: target at " << msg.header.stamp << " came after the cloud at "
                                                << ros::Time().fromNSec(static_cast<std::uint64_t>(targets_.lastCloud()))
                                                << ", which used an older one (receipt order)");
  }

  void onSelector(const ehc_msgs::TargetSelector& msg) {
    try {
      const ehc_control::TargetSelector s = ehc_control::selectorFromMsg(msg);
      if (selector_ && selector_->summary() == s.summary() && selector_object_ == msg.object) return;
      selector_ = s;
      selector_object_ = msg.object;
      if (s.fromCloud()) targets_ = GraspTargetHistory(cfg_.targeting.target_timeout, kMaxTargets);  // another object's
      ROS_INFO_STREAM("ehc_grasp_node: target of '" << msg.object << "': " << s.summary());
    } catch (const std::invalid_argument& e) {
      ROS_ERROR_STREAM("ehc_grasp_node: target selector ignored: " << e.what());
    }
  }

  static StampNs stampNs(const ros::Time& t) { return static_cast<StampNs>(t.toNSec()); }

  /// Every cloud: processed, skipped or dropped (reason logged), then acknowledged once.
  /// In lock-step the targets published before the cloud (by the sequencer, before its
  /// acknowledgement let the simulator go on) are all taken first, whenever they arrived.
  void onCloud(const ros::MessageEvent<const sensor_msgs::PointCloud2>& event) {
    const sensor_msgs::PointCloud2ConstPtr cloud = event.getConstMessage();
    if (lockstep_ && !cfg_.target_topic.empty() && !poll_pass_.wait(ehc_common::kLockstepWallWait))
      ROS_WARN_STREAM_THROTTLE(kLogThrottle, "ehc_grasp_node: roscpp's poll thread did not pass within " << ehc_common::kLockstepWallWait << " wall s");
    target_queue_.callAvailable();
    const double waited = (ros::Time::now() - event.getReceiptTime()).toSec();
    if (!lockstep_ && waited > cfg_.stale_after) {
      ROS_WARN_STREAM_THROTTLE(kLogThrottle, "ehc_grasp_node: cloud at " << cloud->header.stamp << " dropped: it waited "
                                                << waited << " s in the node (stale_after " << cfg_.stale_after << " s)");
      count(FrameOutcome::Stale);
    } else {
      count(process(*cloud));
    }
    ack_.done(cloud->header.stamp);  // after the candidates: the simulator steps on
  }

  void count(FrameOutcome o) { ros_conv::countFrame(&counts_, o, "ehc_grasp_node"); }

  FrameOutcome process(const sensor_msgs::PointCloud2& msg) {
    if (!limiter_.accept(msg.header.stamp.toSec())) return FrameOutcome::RateLimited;
    if (!ehc_common::waitForTransformWall(tf_, cfg_.world_frame, msg.header.frame_id, msg.header.stamp,
                                        lockstep_ ? ehc_common::kLockstepWallWait : cfg_.tf_timeout)) {
      ROS_WARN_STREAM_THROTTLE(kLogThrottle, "ehc_grasp_node: cloud at " << msg.header.stamp << " dropped: no camera pose ('"
                                                << msg.header.frame_id << "' in '" << cfg_.world_frame << "') at its stamp after "
                                                << (lockstep_ ? ehc_common::kLockstepWallWait : cfg_.tf_timeout) << " wall s");
      return FrameOutcome::NoCameraPose;
    }
    CloudPoints read;
    try {  // the point budget first: the points beyond it are never converted
      read = ros_conv::cloudToPoints(msg, static_cast<std::size_t>(cfg_.targeting.max_input_points));
    } catch (const std::invalid_argument& e) {
      ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "ehc_grasp_node: cloud dropped: " << e.what());
      return FrameOutcome::Malformed;
    }
    if (read.read < read.total) counts_.countSubsampled();
    try {
      const geometry_msgs::TransformStamped tf =
          tf_.lookupTransform(cfg_.world_frame, msg.header.frame_id, msg.header.stamp);  // there: waited for above
      const Eigen::Isometry3d T = tf2::transformToEigen(tf);
      const PointList pts = transformPoints(read.points, T);
      const std::optional<Eigen::Vector3d> target = targets_.targetFor(stampNs(msg.header.stamp));
      const bool cloud_target = selector_ && selector_->fromCloud();
      const GraspResult res = cloud_target ? cloudTarget(pts, T, target, msg.header.stamp)
                                           : generateForTarget(gen_, pts, T.translation(), target ? &*target : nullptr, cfg_.targeting);
      ehc_msgs::GraspCandidates out;
      out.header.stamp = msg.header.stamp;
      out.header.frame_id = cfg_.world_frame;
      for (const Grasp& g : res.grasps) {
        out.poses.push_back(ros_conv::toPose(g.pose));
        out.widths.push_back(g.width);
        out.scores.push_back(g.score);
      }
      if (res.grasps.empty())
        ROS_WARN_STREAM_THROTTLE(kLogThrottle, "ehc_grasp_node: no grasp: " << res.reason);
      pub_.publish(out);
      return FrameOutcome::Processed;
    } catch (const std::exception& e) {
      ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "ehc_grasp_node: cloud dropped: " << e.what());
      return FrameOutcome::Failed;
    }
  }

  /// A cloud target's grasps; its pose published, or why there is none logged.
  GraspResult cloudTarget(const PointList& pts, const Eigen::Isometry3d& T_world_cam, const std::optional<Eigen::Vector3d>& tracked,
                          const ros::Time& stamp) {
    const CloudTargetResult r = generateForCloudTarget(gen_, pts, T_world_cam, *selector_, tracked ? &*tracked : nullptr, cfg_.targeting);
    if (!r.selection.selected()) {
      ROS_WARN_STREAM_THROTTLE(kLogThrottle, "ehc_grasp_node: no target: " << r.selection.detail);
      return r.grasps;
    }
    ehc_msgs::CloudTarget m;
    m.header.frame_id = cfg_.world_frame;
    m.header.stamp = stamp;
    m.pose = ros_conv::toPose(ehc_control::cloudTargetPose(r.selection.centre, T_world_cam.translation(), gen_.config().up));
    m.extent_pose = m.pose;  // no extent: half extents 0
    if (const auto extent = cloudTargetExtent(r, T_world_cam.translation(), gen_.config().up)) {
      m.extent_pose = ros_conv::toPose(extent->pose);
      m.half_extents.x = extent->half_extents.x();
      m.half_extents.y = extent->half_extents.y();
      m.half_extents.z = extent->half_extents.z();
    }
    cloud_target_pub_.publish(m);
    return r.grasps;
  }

  GraspNodeConfig cfg_;
  GraspGenerator gen_;
  tf2_ros::Buffer tf_;
  tf2_ros::TransformListener listener_;
  ros::Publisher pub_;
  ros::CallbackQueue target_queue_;  ///< the target subscription's, run when a cloud comes (outlives it)
  ros::Subscriber cloud_sub_, target_sub_, selector_sub_;
  ros::Publisher cloud_target_pub_;
  std::optional<ehc_control::TargetSelector> selector_;  ///< the current object's (selector_topic)
  std::string selector_object_;
  RateLimiter limiter_;  ///< targeting.max_rate_hz on the clouds' stamps
  static constexpr std::size_t kMaxTargets = GraspTargetHistory::kDefaultCapacity;  ///< also the target queue
  GraspTargetHistory targets_;  ///< which target serves which cloud, on their stamps
  ehc_common::PollPassBarrier poll_pass_;
  ehc_common::LockstepAck ack_;
  bool lockstep_ = false;  ///< _ack_topic set: the simulator waits for this node
  FrameCounts counts_{"clouds"};  ///< what became of the clouds (logged)
};

}  // namespace

int main(int argc, char** argv) {
  return ehc_common::runNode(argc, argv, "ehc_grasp_node", 2, [](const ehc_common::NodeParams& params, ros::NodeHandle& nh) {
    const auto cfg = loadGraspNodeConfig(params.requireText("config", "<grasp_node.yaml>"));
    ROS_INFO_STREAM(cfg.summary());
    GraspNode node(nh, params, cfg);
    ehc_common::checkNodeParams(params);
    ros::spin();
    return 0;
  });
}
