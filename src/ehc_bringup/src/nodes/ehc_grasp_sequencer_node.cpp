// ehc_grasp_sequencer_node: thin ROS wrapper of ehc_bringup::GraspSequencer (its parameters:
// SequencerNodeParams; its trace and summary files: GraspTraceWriter, grasp_trace.h).
//   rosrun ehc_bringup ehc_grasp_sequencer_node _config:=config/demo/grasp_sequencer.yaml
//       [_summary:=results/demo/summary.json] [_trace:=results/demo/trace.csv]
//
// Owns the controller's goal: perception publishes each object's pose on its own topic
// (objects[i].pose_topic, e.g. a tag node per object), the sequencer publishes the TCP goal on
// node.goal_topic (/ehc/target_pose) every controller cycle, the current object's filtered pose
// on node.object_pose_topic (the grasp node's target, by remapping), the object's centre on
// node.target_centre_topic (what the controller's camera watches, MPBS), and closes / opens the
// gripper through node.gripper_service (std_srvs/SetBool, true = close). From the descent to
// the pre-grasp until the retreat ends it sends the object's sphere on node.exclusion_topic
// (ehc_msgs/ObstacleExclusion): the obstacle node ignores it, so the fingers may touch the
// object while every other obstacle keeps its damper. One update per
// /ehc/status message (lock-step with the simulator). Reads the gripper result from /sim/status.
// When every object is handled it writes the JSON summary (and the CSV trace) and exits 0.
// Targets without tags: the `_scene:=` file's `targets:` (if any) are the objects' targets at
// the start (as in-process); an ehc_msgs/TargetSelector on node.target_selector_topic sets the target
// of the object it names (GraspSequencer::setTarget; taken with the other inputs at the first
// status after its stamp); the current object's target is published on node.current_target_topic
// (latched) whenever it changes, and while it is a cloud target its poses come from the grasp
// node on node.cloud_target_topic (in place of a tag node's).
// Any exception: log, stop publishing goals (the controller then stops on TARGET_LOST), exit 1.

#include "ehc_common/logging.h"
#include "ehc_bringup/grasp_sequencer.h"
#include "ehc_bringup/grasp_sequencer_node_config.h"
#include "ehc_bringup/grasp_trace.h"
#include "ehc_msgs/CloudTarget.h"
#include "ehc_msgs/ControllerStatus.h"
#include "ehc_msgs/GraspCandidates.h"
#include "ehc_msgs/ObstacleExclusion.h"
#include "ehc_msgs/TargetSelector.h"
#include "ehc_control/target_selector_msg.h"
#include "ehc_control/camera_info_msg.h"
#include "ehc_common/config_node.h"
#include "ehc_control/pose_math.h"
#include "ehc_control/robot_config.h"
#include "ehc_control/whole_body_model.h"
#include "ehc_msgs/SimStatus.h"
#include "ehc_sim/scene_config.h"
#include "ehc_common/lockstep_ack.h"
#include "ehc_common/node_init.h"

#include <geometry_msgs/PointStamped.h>
#include <geometry_msgs/PoseStamped.h>
#include <nav_msgs/Odometry.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/JointState.h>
#include <std_msgs/String.h>
#include <std_srvs/SetBool.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/transform_listener.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <iomanip>
#include <memory>
#include <optional>
#include <utility>

namespace {

using ehc_bringup::GraspSequencer;

using ehc_common::kLogThrottle;

/// The status's motion limit (none, logged, for a string the core does not know).
ehc_control::MotionLimitReport motionLimit(const ehc_msgs::ControllerStatus& m) {
  ehc_control::MotionLimitReport r;
  if (m.motion_limit.empty()) return r;  // a controller that does not report one
  try {
    r.limit = ehc_control::motionLimitFromString(m.motion_limit);
  } catch (const std::invalid_argument& e) {
    ROS_WARN_STREAM_THROTTLE(kLogThrottle, "[ehc_grasp_sequencer_node] " << e.what());
    return r;
  }
  r.joint = m.motion_limit_joint;
  r.link = m.motion_limit_link;
  r.obstacle_point = Eigen::Vector3d(m.motion_limit_obstacle_point.x, m.motion_limit_obstacle_point.y,
                                     m.motion_limit_obstacle_point.z);
  r.value = m.motion_limit_value;
  return r;
}

Eigen::Isometry3d toEigen(const geometry_msgs::Pose& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() << p.position.x, p.position.y, p.position.z;
  // A non-unit quaternion gives a NaN rotation: the core rejects the pose.
  T.linear() = ehc_control::rotationFromQuaternion(
      Eigen::Quaterniond(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z));
  return T;
}

geometry_msgs::PoseStamped toMsg(const Eigen::Isometry3d& T, const std::string& frame, const ros::Time& stamp) {
  geometry_msgs::PoseStamped m;
  m.header.frame_id = frame;
  m.header.stamp = stamp;
  m.pose = tf2::toMsg(T);
  return m;
}

class SequencerNode {
 public:
  SequencerNode(ros::NodeHandle& nh, const ehc_common::NodeParams& params) : listener_(tf_) {
    const std::string config = params.requireText("config", "<grasp_sequencer.yaml>");
    summary_file_ = params.get<std::string>("summary", "");
    trace_file_ = params.get<std::string>("trace", "");
    const auto root = ehc_common::ConfigNode::loadFile(config, "GraspSequencerNode");
    node_ = ehc_bringup::loadSequencerNodeParams(root);
    node_.exit_when_done = params.get("exit_when_done", node_.exit_when_done);
    // The one robot switch: the frames not set in the file come from robot.yaml.
    node_.robot_file = params.getParsed<std::string>("robot", ehc_control::resolveRobotFile).value_or(node_.robot_file);
    const ehc_control::RobotConfig rc = ehc_control::loadRobotConfig(node_.robot_file);
    node_.applyRobotFrames(ehc_control::WholeBodyModel(rc));  // robot.yaml checked against its URDF, frames too
    arm_joints_ = rc.arm_joints;  // the trace's arm speed
    ehc_bringup::GraspSequencerParams sp = ehc_bringup::loadGraspSequencerParams(root);
    root.rejectUnknownKeys();  // both loaders have run: a key neither read is a misspelling
    // The scene names the body of an obstacle that held the robot when a time limit fires, and
    // its `targets:` (if any) are the objects' targets, as in-process.
    const std::string scene = params.get<std::string>("scene", "");
    std::optional<ehc_sim::SceneConfig> scene_config;
    if (!scene.empty()) {
      scene_config = ehc_sim::loadSceneConfig(scene);
      const auto& targets = scene_config->targets;
      if (!targets.empty() && targets.size() != sp.objects.size())
        throw std::invalid_argument("[ehc_grasp_sequencer_node] " + scene + ": scene.targets lists " + std::to_string(targets.size()) +
                                    " target(s) for " + std::to_string(sp.objects.size()) + " sequencer object(s) in " + config);
      for (std::size_t i = 0; i < targets.size(); ++i) sp.objects[i].target = targets[i];
    }
    seq_ = std::make_unique<GraspSequencer>(sp);
    if (scene_config) {
      const std::vector<ehc_sim::BodyConfig> bodies = scene_config->bodies();
      seq_->setObstacleNamer([bodies](const Eigen::Vector3d& p) {
        return ehc_sim::nearestBody(bodies, [&bodies](int i) { return bodies[static_cast<std::size_t>(i)].pose(); }, p);
      });
    }
    std::vector<std::string> inputs = node_.pose_topics;
    for (const auto& t : {node_.status_topic, node_.candidates_topic, node_.sim_status_topic, node_.camera_info_topic,
                          std::string("/tf")})
      inputs.push_back(t);
    ack_ = std::make_unique<ehc_common::LockstepAck>(params, inputs);
    ROS_INFO_STREAM("ehc_grasp_sequencer_node (" << config << ")\n" << sp.summary() << "\n" << node_.summary()
                                                  << (ack_->topic().empty() ? "" : "\n  each status acknowledged on " + ack_->topic()));
    if (!trace_file_.empty()) trace_ = std::make_unique<ehc_bringup::GraspTraceWriter>(trace_file_);
    goal_pub_ = nh.advertise<geometry_msgs::PoseStamped>(node_.goal_topic, 10);
    object_pub_ = nh.advertise<geometry_msgs::PoseStamped>(node_.object_pose_topic, 10);
    centre_pub_ = nh.advertise<geometry_msgs::PointStamped>(node_.target_centre_topic, 10);
    results_pub_ = nh.advertise<std_msgs::String>("ehc/grasp_results", 1, true);  // latched JSON
    gripper_ = nh.serviceClient<std_srvs::SetBool>(node_.gripper_service);
    // No Nagle delay on any input: in lock-step a delayed message arrived a cycle late (sent
    // before the acknowledgement, received after the next status), so runs differed.
    const ros::TransportHints fast = ros::TransportHints().tcpNoDelay();
    // The inputs come on their own queue, taken when a status comes (onStatus) after one
    // receive pass: what was published before the status (a tag pose or candidates before the
    // acknowledgement that let the simulator go on) is then in, whatever the CPU load.
    ros::NodeHandle inputs_nh(nh);
    inputs_nh.setCallbackQueue(&inputs_queue_);
    for (std::size_t i = 0; i < node_.pose_topics.size(); ++i)
      subs_.push_back(inputs_nh.subscribe<geometry_msgs::PoseStamped>(
          node_.pose_topics[i], 5, [this, i](const geometry_msgs::PoseStamped::ConstPtr& m) { onObjectPose(i, *m); },
          ros::VoidConstPtr(), fast));
    subs_.push_back(inputs_nh.subscribe(node_.candidates_topic, 2, &SequencerNode::onCandidates, this, fast));
    current_target_pub_ = nh.advertise<ehc_msgs::TargetSelector>(node_.current_target_topic, 1, true);  // latched
    if (!node_.target_selector_topic.empty())
      subs_.push_back(inputs_nh.subscribe(node_.target_selector_topic, 10, &SequencerNode::onSelector, this, fast));
    subs_.push_back(inputs_nh.subscribe(node_.cloud_target_topic, 5, &SequencerNode::onCloudTarget, this, fast));
    if (!node_.exclusion_topic.empty())
      exclusion_pub_ = nh.advertise<ehc_msgs::ObstacleExclusion>(node_.exclusion_topic, 10);
    subs_.push_back(inputs_nh.subscribe(node_.sim_status_topic, 10, &SequencerNode::onSimStatus, this, fast));
    subs_.push_back(inputs_nh.subscribe(node_.camera_info_topic, 1, &SequencerNode::onCameraInfo, this, fast));
    subs_.push_back(inputs_nh.subscribe("joint_states", 10, &SequencerNode::onJoints, this, fast));
    subs_.push_back(inputs_nh.subscribe("odom", 10, &SequencerNode::onOdom, this, fast));
    subs_.push_back(nh.subscribe(node_.status_topic, 10, &SequencerNode::onStatus, this, fast));
    t_start_ = -1.0;
  }

 private:
  void onObjectPose(std::size_t i, const geometry_msgs::PoseStamped& m) {
    if (!m.header.frame_id.empty() && m.header.frame_id != node_.world_frame) {
      ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "[ehc_grasp_sequencer_node] object pose in frame '" << m.header.frame_id
                                         << "' ignored: expected '" << node_.world_frame << "'");
      return;
    }
    inbox_.add(m.header.stamp, static_cast<int>(i), [this, i, pose = toEigen(m.pose), t = m.header.stamp.toSec()] {
      if (!seq_->setObjectPose(i, t, pose))
        ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "[ehc_grasp_sequencer_node] rejected a non-finite / invalid pose on "
                                           << node_.pose_topics[i]);
      return true;
    });
  }
  void onSelector(const ehc_msgs::TargetSelector& m) {
    const auto& objs = seq_->params().objects;
    const auto it = std::find_if(objs.begin(), objs.end(), [&](const ehc_bringup::GraspObjectSpec& o) { return o.name == m.object; });
    std::size_t index = m.object.empty() ? seq_->currentObject() : static_cast<std::size_t>(it - objs.begin());
    ehc_control::TargetSelector s;
    try {
      if (!m.object.empty() && it == objs.end()) throw std::invalid_argument("no sequencer object '" + m.object + "'");
      s = ehc_control::selectorFromMsg(m);
    } catch (const std::invalid_argument& e) {
      ROS_ERROR_STREAM("[ehc_grasp_sequencer_node] target selector ignored: " << e.what());
      return;
    }
    inbox_.add(m.header.stamp, kSelector, [this, index, s] {
      if (!seq_->setTarget(index, s))
        ROS_ERROR_STREAM("[ehc_grasp_sequencer_node] target selector " << s.summary() << " refused for object " << index
                                                                        << " (handled already, or its grasp is locked)");
      return true;
    });
  }
  /// The current object's pose and extent, if it is a cloud target.
  void onCloudTarget(const ehc_msgs::CloudTarget& m) {
    if (!m.header.frame_id.empty() && m.header.frame_id != node_.world_frame) return;
    ehc_bringup::ObjectExtent extent;
    extent.pose = toEigen(m.extent_pose);
    extent.half_extents = Eigen::Vector3d(m.half_extents.x, m.half_extents.y, m.half_extents.z);
    const bool has_extent = extent.half_extents.norm() > 0.0;
    inbox_.add(m.header.stamp, kCloudTarget, [this, pose = toEigen(m.pose), extent, has_extent, t = m.header.stamp.toSec()] {
      const std::size_t i = seq_->currentObject();
      if (i >= seq_->params().objects.size() || !seq_->params().objects[i].target.fromCloud()) return true;
      if (!seq_->setObjectPose(i, t, pose))
        ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "[ehc_grasp_sequencer_node] rejected a non-finite / invalid cloud target pose");
      else if (has_extent && !seq_->setObjectExtent(i, extent))
        ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "[ehc_grasp_sequencer_node] rejected an invalid cloud target extent");
      return true;
    });
  }
  /// The current object's target on current_target_topic, when it changes.
  void publishCurrentTarget(const ros::Time& stamp) {
    const auto& objs = seq_->params().objects;
    if (seq_->done()) return;
    const ehc_bringup::GraspObjectSpec& o = objs[seq_->currentObject()];
    const std::string key = o.name + " " + o.target.summary();
    if (key == sent_target_) return;
    sent_target_ = key;
    current_target_pub_.publish(ehc_control::selectorToMsg(o.target, o.name, node_.world_frame, stamp));
  }
  void onCandidates(const ehc_msgs::GraspCandidates& m) {
    if (!m.header.frame_id.empty() && m.header.frame_id != node_.world_frame) return;
    std::vector<ehc_bringup::GraspCandidate> c(m.poses.size());
    for (std::size_t i = 0; i < m.poses.size(); ++i) {
      c[i].pose = toEigen(m.poses[i]);
      c[i].width = i < m.widths.size() ? m.widths[i] : std::nan("");
      c[i].score = i < m.scores.size() ? m.scores[i] : std::nan("");
    }
    inbox_.add(m.header.stamp, kCandidates, [this, c, t = m.header.stamp.toSec()] {
      seq_->setGraspCandidates(t, c);
      return true;
    });
  }
  /// world -> `frame` at `stamp` (the status's: in lock-step its tf came with the state), else
  /// the latest (a real robot's tf may lag the controller's clock a little).
  std::optional<Eigen::Isometry3d> lookup(const std::string& frame, const ros::Time& stamp) {
    if (!ack_->topic().empty()) ehc_common::waitForTransformWall(tf_, node_.world_frame, frame, stamp, 1.0);  // lock-step
    for (const ros::Time& t : {stamp, ros::Time(0)}) {
      try {
        return tf2::transformToEigen(tf_.lookupTransform(node_.world_frame, frame, t));
      } catch (const tf2::TransformException& e) {
        if (t.isZero())
          ROS_WARN_STREAM_THROTTLE(kLogThrottle, "[ehc_grasp_sequencer_node] no " << frame << " pose yet: " << e.what());
      }
    }
    return std::nullopt;
  }
  /// Sends the exclusions while there are any, and one empty list when they end.
  void publishExclusions(const std::vector<ehc_bringup::ExclusionSphere>& zones, const ros::Time& stamp) {
    if (node_.exclusion_topic.empty() || (zones.empty() && !excluding_)) return;
    excluding_ = !zones.empty();
    ehc_msgs::ObstacleExclusion m;
    m.header.frame_id = node_.world_frame;
    m.header.stamp = stamp;
    for (const auto& z : zones) {
      geometry_msgs::Point c;
      c.x = z.centre.x();
      c.y = z.centre.y();
      c.z = z.centre.z();
      m.centres.push_back(c);
      m.radii.push_back(z.radius);
    }
    exclusion_pub_.publish(m);
  }
  void onCameraInfo(const sensor_msgs::CameraInfo& m) {
    if (!seq_->setCamera(ehc_control::cameraFromInfo(m)))
      ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "[ehc_grasp_sequencer_node] invalid camera_info ignored");
  }
  void onSimStatus(const ehc_msgs::SimStatus& m) {
    ehc_control::GripperState state;
    try {
      state = ehc_control::gripperStateFromString(m.gripper_state);
    } catch (const std::invalid_argument& e) {
      ROS_ERROR_STREAM_THROTTLE(kLogThrottle, "[ehc_grasp_sequencer_node] " << node_.sim_status_topic
                                                                           << " ignored: " << e.what());
      return;
    }
    inbox_.add(m.header.stamp, kSimStatus, [this, state, ok = m.grasp_succeeded] {
      gripper_state_ = state;
      grasp_succeeded_ = ok;
      return true;
    });
  }
  void onJoints(const sensor_msgs::JointState& m) {  // the trace's arm speed, over the robot's arm joints
    inbox_.add(m.header.stamp, kJoints, [this, speed = ehc_bringup::jointStateArmSpeed(arm_joints_, m.name, m.velocity)] {
      arm_speed_ = speed;
      return true;
    });
  }
  void onOdom(const nav_msgs::Odometry& m) {  // the trace's base speeds
    inbox_.add(m.header.stamp, kOdom, [this, v = std::hypot(m.twist.twist.linear.x, m.twist.twist.linear.y),
                                       w = std::abs(m.twist.twist.angular.z)] {
      base_speed_ = v;
      base_turn_ = w;
      return true;
    });
  }

  void onStatus(const ehc_msgs::ControllerStatus& m) {
    if (!poll_pass_.wait(ehc_common::kLockstepWallWait))
      ROS_WARN_STREAM_THROTTLE(kLogThrottle, "[ehc_grasp_sequencer_node] roscpp's receive thread did not pass within "
                                                 << ehc_common::kLockstepWallWait << " wall s");
    inputs_queue_.callAvailable();
    // Done, or a second status for the state already handled (the controller's watchdog
    // answering a lock-step simulator that waits for a slow perception node, or a state the
    // simulator resent): acknowledged, no second update for one instant.
    if (finished_ || (!inbox_.last().isZero() && m.header.stamp == inbox_.last())) {
      ack_->done(m.header.stamp);  // a simulator waiting for the sequencer goes on
      return;
    }
    try {
      step(m);
      ack_->done(m.header.stamp);
    } catch (const std::exception& e) {
      // No more goals: the controller's target watchdog stops the robot (TARGET_LOST).
      ROS_FATAL_STREAM("[ehc_grasp_sequencer_node] " << e.what() << " -> no more goals, exiting");
      finished_ = failed_ = true;
      ros::shutdown();
    }
  }

 public:
  bool failed() const { return failed_; }

 private:
  void step(const ehc_msgs::ControllerStatus& m) {
    ehc_bringup::SequencerInput in;
    in.t = m.header.stamp.toSec();
    if (t_start_ < 0.0) t_start_ = in.t;
    in.controller_phase = m.phase;
    in.target_in_fov = m.target_in_fov;
    if (std::isfinite(m.sig_omega)) in.sig = m.sig_omega;
    in.gripper_state = gripper_state_;
    in.grasp_succeeded = grasp_succeeded_;
    in.motion_limit = motionLimit(m);
    if (const auto tcp = lookup(node_.tcp_frame, m.header.stamp)) in.tcp = *tcp;
    if (const auto camera = lookup(node_.camera_frame, m.header.stamp)) in.camera = *camera;
    inbox_.takeBefore(m.header.stamp);
    const ehc_bringup::SequencerOutput out = seq_->update(in);
    for (const auto& e : out.events) ROS_INFO_STREAM("[grasp] t=" << std::fixed << std::setprecision(2) << in.t << " " << e);
    const ros::Time now = m.header.stamp;  // every output carries the time it was decided for
    publishCurrentTarget(now);
    if (out.object_pose) object_pub_.publish(toMsg(*out.object_pose, node_.world_frame, now));
    if (out.goal) goal_pub_.publish(toMsg(*out.goal, node_.world_frame, now));
    publishExclusions(out.exclusions, now);
    if (const auto c = seq_->objectCentre()) {
      geometry_msgs::PointStamped p;
      p.header.frame_id = node_.world_frame;
      p.header.stamp = now;
      p.point.x = c->x();
      p.point.y = c->y();
      p.point.z = c->z();
      centre_pub_.publish(p);
    }
    if (out.gripper_command) {
      std_srvs::SetBool srv;
      srv.request.data = *out.gripper_command;
      if (!gripper_.call(srv) || !srv.response.success)
        ROS_ERROR_STREAM("[ehc_grasp_sequencer_node] gripper " << (srv.request.data ? "close" : "open")
                                                               << " failed (" << node_.gripper_service << ")");
    }
    if (trace_) trace_->write(traceRow(m, in.t));
    mode_ = m.mode;
    if (seq_->results().size() != published_results_) {
      published_results_ = seq_->results().size();
      std_msgs::String r;
      r.data = ehc_bringup::graspResultsToJson(seq_->results(), mode_, in.t - t_start_);
      results_pub_.publish(r);
    }
    if (seq_->done()) finish(in.t);
  }

  ehc_bringup::GraspTraceRow traceRow(const ehc_msgs::ControllerStatus& m, double t) const {
    const auto& objs = seq_->params().objects;
    ehc_bringup::GraspTraceRow r;
    r.t = t;
    r.object = objs[std::min(seq_->currentObject(), objs.size() - 1)].name;
    r.phase = seq_->phase();
    r.controller_phase = m.phase;
    r.error_norm = m.error_norm;
    r.position_error = m.position_error;
    r.sig_omega = m.sig_omega;
    r.base_speed = base_speed_;
    r.base_turn = base_turn_;
    r.arm_speed = arm_speed_;
    r.target_in_fov = m.target_in_fov;
    r.obstacle_rows = m.obstacle_rows;
    r.qp_status = m.qp_status;
    return r;
  }

  void finish(double t) {
    finished_ = true;
    const std::string json = ehc_bringup::graspResultsToJson(seq_->results(), mode_, t - t_start_);
    for (const auto& r : seq_->results()) ROS_INFO_STREAM("[grasp] summary " << ehc_bringup::graspResultLine(r));
    ROS_INFO_STREAM("[grasp] json " << json);
    if (!summary_file_.empty() && !ehc_bringup::writeGraspSummaryFile(summary_file_, json))
      ROS_ERROR_STREAM("[ehc_grasp_sequencer_node] cannot write " << summary_file_);
    if (trace_) trace_->flush();
    if (node_.exit_when_done) ros::shutdown();
  }

  ehc_bringup::SequencerNodeParams node_;
  std::vector<std::string> arm_joints_;  ///< the robot's (robot.yaml arm.joints)
  std::unique_ptr<GraspSequencer> seq_;
  tf2_ros::Buffer tf_;
  tf2_ros::TransformListener listener_;
  ros::Publisher goal_pub_, object_pub_, results_pub_, exclusion_pub_, centre_pub_, current_target_pub_;
  std::string sent_target_;  ///< the current target last published (object name + selector)
  std::size_t published_results_ = 0;
  ros::ServiceClient gripper_;
  std::vector<ros::Subscriber> subs_;
  std::unique_ptr<ehc_common::LockstepAck> ack_;  ///< _ack_topic (lock-step acknowledgement gate)
  /// Inputs taken at the first status after their stamp: object poses (source = object index),
  /// grasp candidates, the simulator's gripper status, the trace's speeds.
  static constexpr int kCandidates = 1000000, kSimStatus = 1000001, kJoints = 1000002, kOdom = 1000003,
                       kSelector = 1000004, kCloudTarget = 1000005;
  ehc_common::StampedInbox inbox_;
  ros::CallbackQueue inputs_queue_;  ///< every input but the status (taken in onStatus)
  ehc_common::PollPassBarrier poll_pass_;
  std::string summary_file_, trace_file_, mode_;
  std::unique_ptr<ehc_bringup::GraspTraceWriter> trace_;  ///< _trace:=, else none
  ehc_control::GripperState gripper_state_ = ehc_control::GripperState::Open;
  bool grasp_succeeded_ = false, finished_ = false, failed_ = false, excluding_ = false;
  double arm_speed_ = 0.0, base_speed_ = 0.0, base_turn_ = 0.0, t_start_ = -1.0;
};

}  // namespace

int main(int argc, char** argv) {
  // On an error no more goals come: the controller's target watchdog stops the robot (TARGET_LOST).
  return ehc_common::runNode(argc, argv, "ehc_grasp_sequencer_node", 1, [](const ehc_common::NodeParams& params, ros::NodeHandle& nh) {
    SequencerNode node(nh, params);
    ehc_common::checkNodeParams(params);
    ros::spin();
    return node.failed() ? 1 : 0;
  });
}
