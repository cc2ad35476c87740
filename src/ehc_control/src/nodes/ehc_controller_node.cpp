// ehc_controller_node: thin ROS wrapper of ControllerSupervisor + EhcQpController.
//   rosrun ehc_control ehc_controller_node _config:=config/control/controller.yaml
//       [_robot:=config/robots/realman_rm65_water2/robot.yaml] [_mode:=ehc|neo_e|neo_c|tsmm]
// Subscribes /joint_states, /odom, /ehc/target_pose (PoseStamped in the world frame),
// /ehc/obstacles (optional). Publishes /cmd_vel, /arm/joint_velocity_cmd (stamp = joint state
// stamp), /ehc/status. Cycle: one per joint state (node.trigger: state, lock-step with the
// simulator) or on a timer (node.trigger: timer, real robot). Any stale or invalid input, and
// any QP failure, gives zero commands, repeated every cycle, and a status saying why.

#include "ehc_control/ControllerStatus.h"
#include "ehc_control/JointVelocityCommand.h"
#include "ehc_control/ObstacleArray.h"
#include "ehc_control/config_node.h"
#include "ehc_control/controller_supervisor.h"
#include "ehc_control/pose_servo.h"

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>

#include <cmath>
#include <memory>

namespace {

using namespace ehc_control;

struct NodeParams {
  std::string trigger = "state";  ///< state | timer
  double rate = 100.0;            ///< Hz, timer trigger
  std::string world_frame = "odom";
};

NodeParams loadNodeParams(const ConfigNode& n) {
  NodeParams p;
  p.trigger = n.get<std::string>("trigger", p.trigger);
  if (p.trigger != "state" && p.trigger != "timer") n.fail("trigger", "must be 'state' or 'timer'");
  p.rate = n.get("rate", p.rate);
  requireRange("ControllerNode", "node.rate", p.rate, 1.0, 1000.0);
  return p;
}

class ControllerNode {
 public:
  ControllerNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
    std::string config, robot, mode;
    if (!pnh.getParam("config", config)) throw std::invalid_argument("missing parameter _config:=<controller.yaml>");
    pnh.param<std::string>("robot", robot, "");
    pnh.param<std::string>("mode", mode, "");
    const ConfigNode cfg = ConfigNode::loadFile(config, "ControllerNode");
    if (robot.empty()) robot = cfg.resolvePath(cfg.get<std::string>("robot", "../robots/realman_rm65_water2/robot.yaml"));
    const RobotConfig rc = loadRobotConfig(robot);
    model_ = std::make_shared<const WholeBodyModel>(rc);
    QpControllerParams qp = loadQpControllerParams(cfg.childOrEmpty("controller"));
    if (!mode.empty()) qp.mode = controlModeFromString(mode);
    servo_ = loadPoseServoParams(cfg.childOrEmpty("servo"));
    node_ = loadNodeParams(cfg.childOrEmpty("node"));
    node_.world_frame = rc.world_frame;
    std::shared_ptr<const EhcWeighting> weighting;
    if (!rc.reachability_map_path.empty()) {
      auto map = std::make_shared<const ReachabilityMap>(ReachabilityMap::load(rc.reachability_map_path));
      map->checkCompatible(rc);
      weighting = std::make_shared<const EhcWeighting>(map, loadEhcWeightingParams(cfg.childOrEmpty("weighting")));
      ROS_INFO_STREAM(map->summary());
    }
    controller_ = std::make_unique<EhcQpController>(model_, qp, weighting);
    supervisor_ = std::make_unique<ControllerSupervisor>(rc, loadSupervisorParams(cfg.childOrEmpty("watchdog")));
    ROS_INFO_STREAM("ehc_controller_node\n" << rc.summary() << qp.summary() << "\n  trigger " << node_.trigger
                                            << (node_.trigger == "timer" ? " at " + std::to_string(node_.rate) + " Hz" : ""));

    cmd_vel_ = nh.advertise<geometry_msgs::Twist>("cmd_vel", 1);
    arm_cmd_ = nh.advertise<ehc_control::JointVelocityCommand>("arm/joint_velocity_cmd", 1);
    status_ = nh.advertise<ehc_control::ControllerStatus>("ehc/status", 10);
    subs_.push_back(nh.subscribe("joint_states", 10, &ControllerNode::onJoints, this, ros::TransportHints().tcpNoDelay()));
    subs_.push_back(nh.subscribe("odom", 10, &ControllerNode::onOdom, this, ros::TransportHints().tcpNoDelay()));
    subs_.push_back(nh.subscribe("ehc/target_pose", 10, &ControllerNode::onTarget, this));
    subs_.push_back(nh.subscribe("ehc/obstacles", 10, &ControllerNode::onObstacles, this));
    if (node_.trigger == "timer")
      timer_ = nh.createTimer(ros::Duration(1.0 / node_.rate), [this](const ros::TimerEvent&) { cycle(ros::Time::now()); });
  }

 private:
  void onJoints(const sensor_msgs::JointState& m) {
    const std::string err = supervisor_->setJointState(m.header.stamp.toSec(), m.name, m.position);
    if (!err.empty()) ROS_ERROR_STREAM_THROTTLE(1.0, "[ehc_controller_node] rejected /joint_states: " << err);
    if (node_.trigger == "state") {
      // Lock-step: answer the state once odometry of the same instant has arrived.
      pending_ = m.header.stamp;
      tryCycle();
    }
  }
  void onOdom(const nav_msgs::Odometry& m) {
    const auto& p = m.pose.pose;
    const double yaw = std::atan2(2.0 * (p.orientation.w * p.orientation.z + p.orientation.x * p.orientation.y),
                                  1.0 - 2.0 * (p.orientation.y * p.orientation.y + p.orientation.z * p.orientation.z));
    const std::string err = supervisor_->setBasePose(m.header.stamp.toSec(), Eigen::Vector3d(p.position.x, p.position.y, yaw));
    if (!err.empty()) ROS_ERROR_STREAM_THROTTLE(1.0, "[ehc_controller_node] rejected /odom: " << err);
    odom_stamp_ = m.header.stamp;
    if (node_.trigger == "state") tryCycle();
  }
  void onTarget(const geometry_msgs::PoseStamped& m) {
    if (!m.header.frame_id.empty() && m.header.frame_id != node_.world_frame) {
      ROS_ERROR_STREAM_THROTTLE(1.0, "[ehc_controller_node] rejected target in frame '" << m.header.frame_id
                                         << "': expected '" << node_.world_frame << "'");
      return;
    }
    const auto& p = m.pose;
    const Eigen::Quaterniond qn(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() << p.position.x, p.position.y, p.position.z;
    if (std::abs(qn.norm() - 1.0) > 1e-3 || !std::isfinite(qn.norm())) T.linear().setConstant(std::nan(""));
    else T.linear() = qn.normalized().toRotationMatrix();
    // Receipt time (ROS time): a target is fresh while it keeps arriving.
    const std::string err = supervisor_->setTarget(ros::Time::now().toSec(), T);
    if (!err.empty()) ROS_ERROR_STREAM_THROTTLE(1.0, "[ehc_controller_node] rejected /ehc/target_pose: " << err);
    else if (!have_target_ || !T.isApprox(last_target_, 1e-4)) controller_->reset();
    if (err.empty()) {
      have_target_ = true;
      last_target_ = T;
    }
  }
  void onObstacles(const ehc_control::ObstacleArray& m) {
    std::vector<ObstaclePair> pairs;
    for (const auto& o : m.obstacles) {
      ObstaclePair p;
      p.link = o.link;
      p.link_point << o.link_point.x, o.link_point.y, o.link_point.z;
      p.obstacle_point << o.obstacle_point.x, o.obstacle_point.y, o.obstacle_point.z;
      p.normal << o.normal.x, o.normal.y, o.normal.z;
      p.distance = o.distance;
      pairs.push_back(p);
    }
    const std::string err = supervisor_->setObstacles(ros::Time::now().toSec(), pairs);
    if (!err.empty()) ROS_ERROR_STREAM_THROTTLE(1.0, "[ehc_controller_node] rejected /ehc/obstacles: " << err);
  }

  void tryCycle() {
    if (pending_.isZero() || odom_stamp_ != pending_) return;
    const ros::Time stamp = pending_;
    pending_ = ros::Time();
    cycle(stamp);
  }

  void cycle(const ros::Time& stamp) {
    const double now = ros::Time::now().toSec();
    ehc_control::ControllerStatus st;
    st.header.stamp = stamp;
    st.header.frame_id = node_.world_frame;
    st.mode = toString(controller_->params().mode);
    st.qp_status = "NOT_RUN";
    Eigen::VectorXd v = Eigen::VectorXd::Zero(model_->nDof());
    const SupervisorDecision d = supervisor_->check(now);
    if (!d.run) {
      st.phase = d.phase;
      st.reason = d.reason;
      if (d.phase != "IDLE") ROS_WARN_STREAM_THROTTLE(1.0, "[ehc_controller_node] " << d.phase << ": " << d.reason << " -> zero command");
    } else {
      const auto& rc = model_->config();
      const Eigen::Isometry3d tcp = model_->fk(supervisor_->basePose(), supervisor_->q(), rc.tcp_frame);
      const Vector6d nu = proportionalPoseServo(tcp, supervisor_->target(), servo_);
      const ControllerCommand c = controller_->step(supervisor_->basePose(), supervisor_->q(), supervisor_->target(), nu,
                                                    supervisor_->obstacles(now));
      st.phase = c.ok ? c.phase : "QP_FAILED";
      st.reason = c.failure;
      st.qp_status = c.qp_status;
      st.position_error = c.position_error;
      st.orientation_error = c.orientation_error;
      st.error_norm = c.error_norm;
      st.omega = c.omega;
      st.sig_omega = c.sig;
      st.base_weight = c.base_weight;
      st.solve_time_us = c.solve_time_us;
      st.obstacle_rows = static_cast<uint32_t>(c.obstacle_rows);
      if (c.ok) v = c.velocity;
      else ROS_ERROR_STREAM_THROTTLE(1.0, "[ehc_controller_node] QP_FAILED: " << c.failure << " -> zero command");
    }
    if (!v.allFinite()) v.setZero();  // never publish NaN
    const int nb = model_->nBase();
    geometry_msgs::Twist tw;
    tw.linear.x = v[0];
    if (nb == 3) tw.linear.y = v[1];
    tw.angular.z = v[nb - 1];
    ehc_control::JointVelocityCommand ac;
    ac.header.stamp = stamp;
    ac.names = model_->config().arm_joints;
    ac.velocities.assign(v.data() + nb, v.data() + v.size());
    cmd_vel_.publish(tw);
    arm_cmd_.publish(ac);
    status_.publish(st);
  }

  std::shared_ptr<const WholeBodyModel> model_;
  std::unique_ptr<EhcQpController> controller_;
  std::unique_ptr<ControllerSupervisor> supervisor_;
  PoseServoParams servo_;
  NodeParams node_;
  ros::Publisher cmd_vel_, arm_cmd_, status_;
  std::vector<ros::Subscriber> subs_;
  ros::Timer timer_;
  ros::Time pending_, odom_stamp_;
  bool have_target_ = false;
  Eigen::Isometry3d last_target_ = Eigen::Isometry3d::Identity();
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "ehc_controller_node");
  ros::NodeHandle nh, pnh("~");
  try {
    ControllerNode node(nh, pnh);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM("[ehc_controller_node] " << e.what());
    return 1;
  }
  return 0;
}
