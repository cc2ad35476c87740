#pragma once
// Message conversions of the simulator nodes (ehc_sim_node, ehc_kinematic_sim_node; also used
// by bench_sim): KinematicFakeRobot / SimWorld state -> sensor_msgs / nav_msgs / tf / ehc_msgs
// messages. Header-only, no logic beyond copying.

#include "ehc_control/camera_info_msg.h"  // fillCameraInfo (the camera streams)
#include "ehc_msgs/SimObjectPoses.h"
#include "ehc_msgs/SimStatus.h"
#include "ehc_sim/command_gate.h"
#include "ehc_sim/sim_world.h"
#include "ehc_sim/simulated_camera.h"

#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/JointState.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include <Eigen/Geometry>

#include <cstring>
#include <string>
#include <vector>

namespace ehc_sim {

/// ROS time of a sim time: the simulation starts at 1 s because ROS reads time 0 as "unset".
inline ros::Time rosStamp(std::int64_t sim_ns) {
  ros::Time t;
  t.fromNSec(static_cast<uint64_t>(sim_ns + 1000000000LL));
  return t;
}
inline std::int64_t simNs(const ros::Time& t) {
  return static_cast<std::int64_t>(t.toNSec()) - 1000000000LL;
}

inline geometry_msgs::Pose toPose(const Eigen::Isometry3d& T) {
  geometry_msgs::Pose p;
  p.position.x = T.translation().x();
  p.position.y = T.translation().y();
  p.position.z = T.translation().z();
  const Eigen::Quaterniond q(T.linear());
  p.orientation.x = q.x();
  p.orientation.y = q.y();
  p.orientation.z = q.z();
  p.orientation.w = q.w();
  return p;
}

inline geometry_msgs::Transform toTransform(const Eigen::Isometry3d& T) {
  const geometry_msgs::Pose p = toPose(T);
  geometry_msgs::Transform t;
  t.translation.x = p.position.x;
  t.translation.y = p.position.y;
  t.translation.z = p.position.z;
  t.rotation = p.orientation;
  return t;
}

/// /joint_states: the arm joints, positions and executed velocities.
inline void fillJointState(const KinematicFakeRobot& r, const ros::Time& stamp, sensor_msgs::JointState* m) {
  const auto& cfg = r.robot();
  m->header.stamp = stamp;
  m->name = cfg.arm_joints;
  const Eigen::VectorXd& q = r.armPositions();
  const Eigen::VectorXd v = r.executedVelocity().tail(cfg.nArm());
  m->position.assign(q.data(), q.data() + q.size());
  m->velocity.assign(v.data(), v.data() + v.size());
  m->effort.clear();
}

/// A base pose (x, y, yaw in the world) and twist (vx, vy, wz in the base frame) as an Odometry
/// message odom -> base_link.
inline void fillBaseOdometry(const ehc_control::RobotConfig& cfg, const ros::Time& stamp, const Eigen::Vector3d& pose,
                             const Eigen::Vector3d& twist, nav_msgs::Odometry* m) {
  m->header.stamp = stamp;
  m->header.frame_id = cfg.world_frame;
  m->child_frame_id = cfg.base_frame;
  m->pose.pose = toPose(ehc_control::WholeBodyModel::baseTransform(pose));
  m->twist.twist.linear.x = twist[0];
  m->twist.twist.linear.y = twist[1];
  m->twist.twist.angular.z = twist[2];
}

/// /odom: the pose and twist as the base model's odometry reports them (ideal: the true pose and
/// the executed twist; water2: the bridge's estimate).
inline void fillOdometry(const KinematicFakeRobot& r, const ros::Time& stamp, nav_msgs::Odometry* m) {
  fillBaseOdometry(r.robot(), stamp, r.odometryPose(), r.odometryTwist(), m);
}

/// Ground truth for metrics (the hardware stand-in's /sim/base_pose): the TRUE base pose in the
/// world (odom) frame and the executed base twist (base frame); never an input of the stack.
inline void fillTrueBase(const KinematicFakeRobot& r, const ros::Time& stamp, nav_msgs::Odometry* m) {
  const auto& cfg = r.robot();
  const Eigen::VectorXd& v = r.executedVelocity();
  fillBaseOdometry(cfg, stamp, r.basePose(), Eigen::Vector3d(v[0], cfg.nBase() > 2 ? v[1] : 0.0, v[cfg.nBase() - 1]), m);
}

/// odom -> base_link (the robot's world and base frames), from the odometry as /odom (on the
/// robot the bridge publishes this tf from its estimate).
inline void fillBaseTransform(const KinematicFakeRobot& r, const ros::Time& stamp, geometry_msgs::TransformStamped* t) {
  t->header.stamp = stamp;
  t->header.frame_id = r.robot().world_frame;
  t->child_frame_id = r.robot().base_frame;
  t->transform = toTransform(ehc_control::WholeBodyModel::baseTransform(r.odometryPose()));
}

/// odom -> base_link, then every URDF link relative to its parent.
inline void fillTransforms(const SimWorld& w, const ros::Time& stamp,
                           std::vector<geometry_msgs::TransformStamped>* out) {
  const auto& links = w.collisionModel().allLinks();
  out->resize(links.size());
  std::size_t k = 0;
  for (const std::string& link : links) {
    geometry_msgs::TransformStamped& t = (*out)[k++];
    t.header.stamp = stamp;
    const std::string& parent = w.collisionModel().parentOf(link);
    if (parent.empty()) {
      fillBaseTransform(w.robot(), stamp, &t);
      t.child_frame_id = link;  // the URDF root
    } else {
      t.header.frame_id = parent;
      t.child_frame_id = link;
      t.transform = toTransform(w.linkPoseInParent(link));
    }
  }
}

inline void fillImage(const vpImage<unsigned char>& I, const std::string& frame, const ros::Time& stamp,
                      sensor_msgs::Image* m) {
  m->header.stamp = stamp;
  m->header.frame_id = frame;
  m->height = I.getHeight();
  m->width = I.getWidth();
  m->encoding = "mono8";
  m->is_bigendian = 0;
  m->step = I.getWidth();
  m->data.resize(I.getSize());
  std::memcpy(m->data.data(), I.bitmap, I.getSize());
}

inline void fillCloud(const std::vector<Eigen::Vector3f>& pts, const std::string& frame,
                      const ros::Time& stamp, sensor_msgs::PointCloud2* m) {
  m->header.stamp = stamp;
  m->header.frame_id = frame;
  sensor_msgs::PointCloud2Modifier mod(*m);
  mod.setPointCloud2FieldsByString(1, "xyz");
  mod.resize(pts.size());
  m->height = 1;
  m->width = static_cast<uint32_t>(pts.size());
  m->is_dense = true;
  sensor_msgs::PointCloud2Iterator<float> x(*m, "x"), y(*m, "y"), z(*m, "z");
  for (const auto& p : pts) {
    *x = p.x();
    *y = p.y();
    *z = p.z();
    ++x;
    ++y;
    ++z;
  }
}

inline void fillObjectPoses(const SimWorld& w, const ros::Time& stamp, ehc_msgs::SimObjectPoses* m) {
  const auto& objects = w.scene().objects;
  m->header.stamp = stamp;
  m->header.frame_id = w.model().config().world_frame;
  m->names.resize(objects.size());
  m->poses.resize(objects.size());
  m->tag_ids.resize(objects.size());
  m->tag_sizes.resize(objects.size());
  m->tag_poses.resize(objects.size());
  m->held.resize(objects.size());
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const int b = w.objectBodyIndex(static_cast<int>(i));
    m->names[i] = objects[i].name;
    m->poses[i] = toPose(w.bodyPose(b));
    m->tag_ids[i] = objects[i].tag.enabled ? objects[i].tag.id : -1;
    m->tag_sizes[i] = objects[i].tag.enabled ? objects[i].tag.size : 0.0;
    m->tag_poses[i] = objects[i].tag.enabled ? toPose(w.tagPose(b)) : m->poses[i];
    m->held[i] = w.gripper().heldObject() == static_cast<int>(i);
  }
}

/// The /sim/status fields every fake robot has: step, mode, command counters. The rest (the
/// collisions and the gripper) stays empty (ehc_kinematic_sim_node has neither).
inline void fillCommandStatus(const KinematicFakeRobot& robot, const CommandGate& gate, bool lock_step,
                              std::int64_t steps, const ros::Time& stamp, ehc_msgs::SimStatus* m) {
  m->header.stamp = stamp;
  m->step = static_cast<uint64_t>(steps);
  m->lock_step = lock_step;
  m->base_commands_rejected = static_cast<uint64_t>(gate.counters().base_rejected);
  m->arm_commands_rejected = static_cast<uint64_t>(gate.counters().arm_rejected);
  m->arm_commands_stale = static_cast<uint64_t>(gate.counters().arm_stale);
  m->commands_saturated = static_cast<uint64_t>(robot.saturatedCommands());
  m->joint_limit_clamps = static_cast<uint64_t>(robot.jointLimitClamps());
}

inline void fillStatus(const SimWorld& w, const CommandGate& gate, bool lock_step,
                       const ros::Time& stamp, ehc_msgs::SimStatus* m) {
  fillCommandStatus(w.robot(), gate, lock_step, static_cast<std::int64_t>(w.stepCount()), stamp, m);
  const StepReport& r = w.lastStep();
  m->robot_world_collision = r.robot_world_collision;
  m->self_collision = r.self_collision;
  m->collision_steps = static_cast<uint64_t>(w.counters().collision_steps);
  m->self_collision_steps = static_cast<uint64_t>(w.counters().self_collision_steps);
  m->colliding_pairs.clear();
  for (const auto& c : r.collisions) m->colliding_pairs.push_back(c.a + "|" + c.b);
  const ParallelGripper& g = w.gripper();
  m->gripper_state = ehc_control::toString(g.state());  // the one string map
  m->gripper_opening = g.opening();
  m->held_object = g.heldObject() >= 0 ? w.scene().objects[static_cast<std::size_t>(g.heldObject())].name : "";
  m->grasp_succeeded = g.graspSucceeded();
  m->grasp_successes = static_cast<uint64_t>(g.graspSuccesses());
  m->grasp_failures = static_cast<uint64_t>(g.graspFailures());
}

}  // namespace ehc_sim
