// ehc_kinematic_sim_node: the noisy kinematic fake robot (ehc_sim::KinematicFakeRobot) as a
// ROS node with a lock-step /clock, for controller tests and tools (no physics, no camera; the
// Bullet simulator is ehc_sim's ehc_sim_node).
//   rosrun ehc_sim ehc_kinematic_sim_node _config:=sim.yaml [_robot:=robot.yaml]
// Lock-step: publishes the state at sim time t (/clock, /odom, tf odom->base_link,
// /joint_states stamped t), waits for the /arm/joint_velocity_cmd stamped t and one /cmd_vel,
// then advances by dt. If no command arrives within lockstep_timeout_wall seconds (controller
// dead or stopped), it advances with a zero command, so time keeps running.

#include "ehc_msgs/JointVelocityCommand.h"
#include "ehc_control/config_node.h"
#include "ehc_sim/kinematic_fake_robot.h"

#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/JointState.h>
#include <tf2_ros/transform_broadcaster.h>

#include <chrono>
#include <cmath>
#include <thread>

namespace {

struct KinematicSimParams {
  double dt = 0.01;                      ///< s per step
  bool lockstep = true;
  double lockstep_timeout_wall = 1.0;    ///< s of wall time without a command -> zero step
  bool noise = false;
  ehc_sim::ActuationNoise noise_model;   ///< Table I sigmas
  unsigned seed = 1;
  Eigen::Vector3d initial_base = Eigen::Vector3d::Zero();
};

KinematicSimParams loadParams(const ehc_control::ConfigNode& n) {
  KinematicSimParams p;
  p.dt = n.get("dt", p.dt);
  ehc_control::requireRange("KinematicSimParams", "sim.dt", p.dt, 1e-4, 0.1);
  p.lockstep = n.get("lockstep", p.lockstep);
  p.lockstep_timeout_wall = n.get("lockstep_timeout_wall", p.lockstep_timeout_wall);
  ehc_control::requireRange("KinematicSimParams", "sim.lockstep_timeout_wall", p.lockstep_timeout_wall, 0.01, 60.0);
  p.noise = n.get("noise", p.noise);
  p.noise_model.base_translation = n.get("noise_base_translation", p.noise_model.base_translation);
  p.noise_model.base_rotation = n.get("noise_base_rotation", p.noise_model.base_rotation);
  p.noise_model.arm = n.get("noise_arm", p.noise_model.arm);
  p.noise_model.enabled = p.noise;
  p.noise_model.validate();
  p.seed = static_cast<unsigned>(n.get<int>("seed", 1));
  p.initial_base = n.getVector("initial_base", p.initial_base, 3);
  return p;
}

class KinematicSimNode {
 public:
  KinematicSimNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
    std::string config, robot;
    if (!pnh.getParam("config", config)) throw std::invalid_argument("missing parameter _config:=<sim.yaml>");
    const auto cfg = ehc_control::ConfigNode::loadFile(config, "KinematicSimNode");
    pnh.param<std::string>("robot", robot, "");
    if (robot.empty()) robot = cfg.resolvePath(cfg.require<std::string>("robot"));
    rc_ = ehc_control::loadRobotConfig(robot);
    p_ = loadParams(cfg.childOrEmpty("sim"));
    robot_ = std::make_unique<ehc_sim::KinematicFakeRobot>(rc_, p_.noise_model, p_.seed);
    robot_->reset(p_.initial_base, rc_.arm_ready, p_.seed);
    ROS_INFO_STREAM("ehc_kinematic_sim_node: dt " << p_.dt << " s, lockstep " << p_.lockstep << ", noise "
                                                  << p_.noise << ", seed " << p_.seed);
    clock_ = nh.advertise<rosgraph_msgs::Clock>("clock", 1);
    joints_ = nh.advertise<sensor_msgs::JointState>("joint_states", 1);
    odom_ = nh.advertise<nav_msgs::Odometry>("odom", 1);
    subs_.push_back(nh.subscribe("cmd_vel", 10, &KinematicSimNode::onCmdVel, this, ros::TransportHints().tcpNoDelay()));
    subs_.push_back(nh.subscribe("arm/joint_velocity_cmd", 10, &KinematicSimNode::onArm, this, ros::TransportHints().tcpNoDelay()));
    command_ = Eigen::VectorXd::Zero(robot_->nDof());
  }

  void run() {
    // Give subscribers a moment to connect before time starts.
    ros::WallDuration(0.5).sleep();
    while (ros::ok()) {
      publishState();
      const auto t0 = std::chrono::steady_clock::now();
      bool answered = false;
      while (ros::ok()) {
        ros::spinOnce();
        answered = arm_stamp_ == t_ && cmd_vel_count_ > 0;
        if (!p_.lockstep) break;
        if (answered) break;
        if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > p_.lockstep_timeout_wall) break;
        std::this_thread::sleep_for(std::chrono::microseconds(50));
      }
      if (!p_.lockstep) ros::WallDuration(p_.dt).sleep();
      Eigen::VectorXd cmd = answered || !p_.lockstep ? command_ : Eigen::VectorXd::Zero(robot_->nDof());
      if (!answered && p_.lockstep) ++missed_;
      try {
        robot_->step(cmd, p_.dt);
      } catch (const std::exception& e) {
        ROS_ERROR_STREAM_THROTTLE(1.0, "[ehc_kinematic_sim_node] " << e.what());
        robot_->step(Eigen::VectorXd::Zero(robot_->nDof()), p_.dt);
      }
      cmd_vel_count_ = 0;
      t_ += ros::Duration(p_.dt);
    }
  }

 private:
  void onCmdVel(const geometry_msgs::Twist& m) {
    const int nb = rc_.nBase();
    const Eigen::Vector3d v(m.linear.x, m.linear.y, m.angular.z);
    if (!v.allFinite()) {
      ROS_ERROR_THROTTLE(1.0, "[ehc_kinematic_sim_node] rejected non-finite /cmd_vel");
      return;
    }
    command_[0] = v[0];
    if (nb == 3) command_[1] = v[1];
    command_[nb - 1] = v[2];
    ++cmd_vel_count_;
  }
  void onArm(const ehc_msgs::JointVelocityCommand& m) {
    if (m.velocities.size() != static_cast<std::size_t>(rc_.nArm()) || m.names != rc_.arm_joints) {
      ROS_ERROR_THROTTLE(1.0, "[ehc_kinematic_sim_node] rejected arm command: wrong joint names or size");
      return;
    }
    for (double v : m.velocities)
      if (!std::isfinite(v)) {
        ROS_ERROR_THROTTLE(1.0, "[ehc_kinematic_sim_node] rejected non-finite arm command");
        return;
      }
    for (int i = 0; i < rc_.nArm(); ++i) command_[rc_.nBase() + i] = m.velocities[static_cast<std::size_t>(i)];
    arm_stamp_ = m.header.stamp;
  }

  void publishState() {
    rosgraph_msgs::Clock c;
    c.clock = t_;
    clock_.publish(c);
    const Eigen::Vector3d b = robot_->basePose();
    const Eigen::VectorXd v = robot_->executedVelocity();
    nav_msgs::Odometry o;
    o.header.stamp = t_;
    o.header.frame_id = rc_.world_frame;
    o.child_frame_id = rc_.base_frame;
    o.pose.pose.position.x = b.x();
    o.pose.pose.position.y = b.y();
    o.pose.pose.orientation.z = std::sin(b.z() / 2);
    o.pose.pose.orientation.w = std::cos(b.z() / 2);
    o.twist.twist.linear.x = v[0];
    if (rc_.nBase() == 3) o.twist.twist.linear.y = v[1];
    o.twist.twist.angular.z = v[rc_.nBase() - 1];
    odom_.publish(o);
    geometry_msgs::TransformStamped tf;
    tf.header = o.header;
    tf.child_frame_id = rc_.base_frame;
    tf.transform.translation.x = b.x();
    tf.transform.translation.y = b.y();
    tf.transform.rotation = o.pose.pose.orientation;
    tf_.sendTransform(tf);
    sensor_msgs::JointState j;
    j.header.stamp = t_;
    j.name = rc_.arm_joints;
    const Eigen::VectorXd q = robot_->armPositions();
    j.position.assign(q.data(), q.data() + q.size());
    j.velocity.assign(v.data() + rc_.nBase(), v.data() + v.size());
    joints_.publish(j);
  }

  ehc_control::RobotConfig rc_;
  KinematicSimParams p_;
  std::unique_ptr<ehc_sim::KinematicFakeRobot> robot_;
  ros::Publisher clock_, joints_, odom_;
  std::vector<ros::Subscriber> subs_;
  tf2_ros::TransformBroadcaster tf_;
  Eigen::VectorXd command_;
  ros::Time t_ = ros::Time(1.0);
  ros::Time arm_stamp_;
  int cmd_vel_count_ = 0;
  long missed_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "ehc_kinematic_sim_node");
  ros::NodeHandle nh, pnh("~");
  try {
    KinematicSimNode node(nh, pnh);
    node.run();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("[ehc_kinematic_sim_node] " << e.what());
    return 1;
  }
  return 0;
}
