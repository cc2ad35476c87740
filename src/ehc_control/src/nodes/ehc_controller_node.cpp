// ehc_controller_node: thin ROS wrapper of ControllerSupervisor + MPBS/PBVS servo + EhcQpController.
//   rosrun ehc_control ehc_controller_node _config:=config/control/controller.yaml
//       [_robot:=config/robots/realman_rm65_water2/robot.yaml] [_mode:=ehc|neo_e|neo_c|tsmm]
//       [_servo:=pbvs|proportional] [_mpbs:=true|false] [_target_timeout:=<s>]
// Subscribes /joint_states, /odom, /ehc/target_pose (PoseStamped in the world frame: the TCP goal,
// e.g. the grasp pose), /ehc/obstacles (optional), /ehc/target_centre (optional PointStamped in
// the world frame: the object centre the camera watches, when it is not the goal's origin, e.g.
// while the goal is a pre-grasp pose). Publishes /cmd_vel, /arm/joint_velocity_cmd (stamp =
// joint state stamp), /ehc/status (incl. target_in_fov, tfm, target_age). Cycle: one per joint
// state (node.trigger: state, lock-step with the simulator) or on a timer (node.trigger: timer,
// real robot). The last good target pose is served while it is younger than
// watchdog.target_timeout; older -> TARGET_LOST and zero commands until a fresh pose arrives.
// Any stale or invalid input, and any servo or QP failure, gives zero commands, repeated every
// cycle, and a status saying why.

#include "ehc_msgs/ControllerStatus.h"
#include "ehc_msgs/JointVelocityCommand.h"
#include "ehc_msgs/ObstacleArray.h"
#include "ehc_control/config_node.h"
#include "ehc_control/controller_supervisor.h"
#include "ehc_control/mpbs.h"
#include "ehc_control/pose_servo.h"
#include "ehc_control/target_tracker.h"

#include <geometry_msgs/PointStamped.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>

#include <cmath>
#include <memory>
#include <optional>
#include <sstream>

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

enum class ServoType { Proportional, Pbvs };

ServoType servoTypeFromString(const std::string& s) {
  if (s == "proportional") return ServoType::Proportional;
  if (s == "pbvs") return ServoType::Pbvs;
  throw std::invalid_argument("[ControllerNode] servo type must be 'proportional' or 'pbvs' (got '" + s + "')");
}

struct TrackingNodeParams {
  double centre_timeout = 1.0;  ///< s: a /ehc/target_centre older than this is ignored
};

TrackingNodeParams loadTrackingNodeParams(const ConfigNode& n) {
  TrackingNodeParams p;
  p.centre_timeout = n.get("centre_timeout", p.centre_timeout);
  requireRange("ControllerNode", "tracking.centre_timeout", p.centre_timeout, 1e-3, 3600.0);
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

    // Servo: proportional (NEO p_servo) or ViSP PBVS, with or without MPBS.
    const ConfigNode servo_cfg = cfg.childOrEmpty("servo");
    std::string servo_type = servo_cfg.get<std::string>("type", "proportional");
    pnh.param<std::string>("servo", servo_type, servo_type);
    try {
      servo_type_ = servoTypeFromString(servo_type);
    } catch (const std::invalid_argument&) {
      servo_cfg.fail("type", "must be 'proportional' or 'pbvs' (got '" + servo_type + "')");
    }
    servo_ = loadPoseServoParams(servo_cfg);
    const PbvsServoParams pbvs = loadPbvsServoParams(servo_cfg);
    MpbsParams mpbs = loadMpbsParams(cfg.childOrEmpty("mpbs"));
    if (pnh.hasParam("mpbs")) pnh.getParam("mpbs", mpbs.enabled);
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
    SupervisorParams sup = loadSupervisorParams(cfg.childOrEmpty("watchdog"));
    if (pnh.hasParam("target_timeout")) {
      pnh.getParam("target_timeout", sup.target_timeout);
      sup.validate();
    }
    supervisor_ = std::make_unique<ControllerSupervisor>(rc, sup);

    // Camera: mount on the hand (URDF) and intrinsics (tracking.camera) for MPBS and TfM.
    if (!model_->hasLink(rc.camera_frame) || !model_->hasLink(rc.tcp_frame))
      throw std::invalid_argument("[ControllerNode] camera frame '" + rc.camera_frame + "' or TCP frame '" +
                                  rc.tcp_frame + "' is not in the URDF");
    const Eigen::Isometry3d tcp_T_camera = model_->linkPoseInBase(rc.arm_ready, rc.tcp_frame).inverse() *
                                           model_->linkPoseInBase(rc.arm_ready, rc.camera_frame);
    const ConfigNode tracking_cfg = cfg.childOrEmpty("tracking");
    const TargetTrackerParams tracking = loadTargetTrackerParams(tracking_cfg);
    tracking_ = loadTrackingNodeParams(tracking_cfg);
    const PinholeCamera camera = tracking.camera_file.empty() ? PinholeCamera{} : loadPinholeCamera(tracking.camera_file);
    tracker_ = std::make_unique<TargetTracker>(camera, tracking);
    if (servo_type_ == ServoType::Pbvs && mpbs.enabled && !controller_->hasWeighting())
      throw std::invalid_argument("[ControllerNode] mpbs.enabled needs sig(omega), i.e. a reachability map in robot.yaml");
    mpbs_ = std::make_unique<MpbsServo>(tcp_T_camera, pbvs, mpbs);
    roll_index_ = findRollJoint(*model_);

    std::ostringstream servo_summary;
    if (servo_type_ == ServoType::Pbvs)
      servo_summary << pbvs.summary() << "\n  " << mpbs.summary();
    else
      servo_summary << "servo: proportional (gain " << servo_.gain << ", rotation ratio " << servo_.rotation_gain_ratio
                    << ", roll unwinding " << (servo_.unwind_roll ? "on" : "off") << "); mpbs: n/a";
    ROS_INFO_STREAM("ehc_controller_node\n"
                    << rc.summary() << qp.summary() << "\n  " << servo_summary.str() << "\n  roll joint "
                    << (roll_index_ >= 0 ? rc.arm_joints[static_cast<std::size_t>(roll_index_)] : std::string("none"))
                    << "\n  " << tracking.summary() << ", " << camera.summary() << ", centre timeout "
                    << tracking_.centre_timeout << " s\n  watchdog: state " << sup.state_timeout << " s, target "
                    << sup.target_timeout << " s, obstacles " << sup.obstacle_timeout << " s\n  trigger "
                    << node_.trigger << (node_.trigger == "timer" ? " at " + std::to_string(node_.rate) + " Hz" : ""));

    cmd_vel_ = nh.advertise<geometry_msgs::Twist>("cmd_vel", 1);
    arm_cmd_ = nh.advertise<ehc_msgs::JointVelocityCommand>("arm/joint_velocity_cmd", 1);
    status_ = nh.advertise<ehc_msgs::ControllerStatus>("ehc/status", 10);
    subs_.push_back(nh.subscribe("joint_states", 10, &ControllerNode::onJoints, this, ros::TransportHints().tcpNoDelay()));
    subs_.push_back(nh.subscribe("odom", 10, &ControllerNode::onOdom, this, ros::TransportHints().tcpNoDelay()));
    subs_.push_back(nh.subscribe("ehc/target_pose", 10, &ControllerNode::onTarget, this));
    subs_.push_back(nh.subscribe("ehc/target_centre", 10, &ControllerNode::onTargetCentre, this));
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
  void onTargetCentre(const geometry_msgs::PointStamped& m) {
    const Eigen::Vector3d c(m.point.x, m.point.y, m.point.z);
    if ((!m.header.frame_id.empty() && m.header.frame_id != node_.world_frame) || !c.allFinite()) {
      ROS_ERROR_STREAM_THROTTLE(1.0, "[ehc_controller_node] rejected /ehc/target_centre (frame '"
                                         << m.header.frame_id << "', expected '" << node_.world_frame
                                         << "', finite " << c.allFinite() << ")");
      return;
    }
    centre_ = c;
    t_centre_ = ros::Time::now().toSec();
  }
  void onObstacles(const ehc_msgs::ObstacleArray& m) {
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

  /// The point the camera watches: /ehc/target_centre while fresh, else the target's centre.
  Eigen::Vector3d targetCentre(double now) const {
    if (t_centre_ && now - *t_centre_ <= tracking_.centre_timeout && now - *t_centre_ >= -tracking_.centre_timeout)
      return centre_;
    return mpbs_->targetCentre(supervisor_->target());
  }

  void cycle(const ros::Time& stamp) {
    const double now = ros::Time::now().toSec();
    ehc_msgs::ControllerStatus st;
    st.header.stamp = stamp;
    st.header.frame_id = node_.world_frame;
    st.mode = toString(controller_->params().mode);
    st.qp_status = "NOT_RUN";
    st.target_age = supervisor_->targetAge(now);
    Eigen::VectorXd v = Eigen::VectorXd::Zero(model_->nDof());
    const SupervisorDecision d = supervisor_->check(now);
    try {
      // TfM: every cycle with a target (served or lost), camera pose from the kinematics.
      if (supervisor_->hasTarget() && (d.run || d.phase == "TARGET_LOST")) {
        const Eigen::Vector3d centre = targetCentre(now);
        if (tracker_->setTarget(centre))
          ROS_INFO_STREAM("[ehc_controller_node] new target centre [" << centre.transpose() << "]: TfM restarts");
        st.target_in_fov = tracker_->observe(
            model_->fk(supervisor_->basePose(), supervisor_->q(), model_->config().camera_frame));
      }
      st.tfm = tracker_->tfm();
      if (!d.run) {
        st.phase = d.phase;
        st.reason = d.reason;
        if (d.phase != "IDLE") ROS_WARN_STREAM_THROTTLE(1.0, "[ehc_controller_node] " << d.phase << ": " << d.reason << " -> zero command");
      } else {
        const ControllerCommand c = step(now);
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
    } catch (const std::exception& e) {  // core errors: stop safely, say why
      v.setZero();
      st.phase = "STOPPED";
      st.reason = std::string("controller error: ") + e.what();
      st.qp_status = "NOT_RUN";
      ROS_ERROR_STREAM_THROTTLE(1.0, "[ehc_controller_node] " << e.what() << " -> zero command");
    }
    if (!v.allFinite()) v.setZero();  // never publish NaN
    const int nb = model_->nBase();
    geometry_msgs::Twist tw;
    tw.linear.x = v[0];
    if (nb == 3) tw.linear.y = v[1];
    tw.angular.z = v[nb - 1];
    ehc_msgs::JointVelocityCommand ac;
    ac.header.stamp = stamp;
    ac.names = model_->config().arm_joints;
    ac.velocities.assign(v.data() + nb, v.data() + v.size());
    cmd_vel_.publish(tw);
    arm_cmd_.publish(ac);
    status_.publish(st);
  }

  /// Servo (proportional or PBVS/MPBS) + QP for the current state and target.
  ControllerCommand step(double now) {
    const auto& rc = model_->config();
    const Eigen::Vector3d& base = supervisor_->basePose();
    const Eigen::VectorXd& q = supervisor_->q();
    const Eigen::Isometry3d& target = supervisor_->target();
    const Eigen::Isometry3d tcp = model_->fk(base, q, rc.tcp_frame);
    RollJoint roll;
    if (roll_index_ >= 0) {
      roll.q = q[roll_index_];
      roll.lower = rc.arm_lower[roll_index_];
      roll.upper = rc.arm_upper[roll_index_];
    }
    const RollJoint* roll_ptr = roll_index_ >= 0 ? &roll : nullptr;
    const auto obstacles = supervisor_->obstacles(now);
    if (servo_type_ == ServoType::Proportional)
      return controller_->step(base, q, target, proportionalPoseServo(tcp, target, servo_, roll_ptr), obstacles);
    // sig(omega) once per cycle, shared by MPBS (eq. 14) and the QP weighting.
    std::optional<EhcWeight> w;
    if (controller_->hasWeighting()) w = controller_->weight(base, tcp.translation(), target.translation());
    const Eigen::Vector3d centre = targetCentre(now);
    const MpbsOutput out = mpbs_->compute(tcp, target, w ? w->sig : 1.0, roll_ptr, &centre);
    return controller_->step(base, q, target, out.twist, obstacles, w ? &*w : nullptr);
  }

  std::shared_ptr<const WholeBodyModel> model_;
  std::unique_ptr<EhcQpController> controller_;
  std::unique_ptr<ControllerSupervisor> supervisor_;
  std::unique_ptr<MpbsServo> mpbs_;
  std::unique_ptr<TargetTracker> tracker_;
  ServoType servo_type_ = ServoType::Proportional;
  PoseServoParams servo_;
  TrackingNodeParams tracking_;
  NodeParams node_;
  int roll_index_ = -1;
  ros::Publisher cmd_vel_, arm_cmd_, status_;
  std::vector<ros::Subscriber> subs_;
  ros::Timer timer_;
  ros::Time pending_, odom_stamp_;
  bool have_target_ = false;
  Eigen::Isometry3d last_target_ = Eigen::Isometry3d::Identity();
  Eigen::Vector3d centre_ = Eigen::Vector3d::Zero();
  std::optional<double> t_centre_;
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
