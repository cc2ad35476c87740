// ehc_hardware_standin_node: the Bullet simulator standing in for the RealMan HARDWARE behind its
// real interfaces (deployment rehearsal, REALMAN.md): ROS wrapper of ehc_sim::HardwareStandIn
// (rm_driver + Water2 behaviour) and ehc_sim::Water2ApiServer (the Water2 TCP API on
// 127.0.0.1). The unchanged rm_arm_adapter and water2_base_bridge talk to it exactly as to the
// robot; the rest of the stack (robot_state_publisher, perception, controller) runs as
// run_realman.sh starts it on the robot. Wall clock, no /clock (use_sim_time false), as the
// hardware: the world is stepped by sim.dt until it has caught up with the wall clock.
//
//   rosrun ehc_sim ehc_hardware_standin_node _config:=config/realman/hardware_standin.yaml
//       [_scene:=config/scenes/table_three_objects.yaml] [_port:=31001] [_seed:=N]
// (_free_run is accepted and meaningless here: the hardware never waits for anyone.)
//
// _port 0 (default): an ephemeral port; the port in use is set as the private parameter
// ~water2_port (read it before pointing the bridge at it: WATER2_PORT=... run_realman.sh).
// As the rm_driver: subscribes /rm_driver/JointPos, /rm_driver/Emergency_Stop,
// /rm_driver/Gripper_Set, /rm_driver/Gripper_Pick; publishes /joint_states (joint1..joint6).
// As the D435 driver: /camera/color/image_raw (mono8), /camera/color/camera_info,
// /camera/depth/points. As the simulator (metrics and the sequencer's grasp result only):
// /sim/status, /sim/object_poses, /sim/base_pose (nav_msgs/Odometry: the TRUE base pose and
// executed twist) and /sim/tcp_pose (geometry_msgs/PoseStamped: the TRUE TCP in the world), for
// the rehearsal's odometry and closing-distance figures. Not published here (the real nodes do it): /odom, /tf.

#include "sim_camera_streams.h"
#include "sim_ros_conversions.h"

#include "ehc_sim/hardware_stand_in.h"
#include "ehc_sim/water2_api_server.h"

#include "ehc_common/node_init.h"

#include <geometry_msgs/PoseStamped.h>
#include <rm_msgs/Gripper_Pick.h>
#include <rm_msgs/Gripper_Set.h>
#include <rm_msgs/JointPos.h>
#include <rm_msgs/Stop.h>
#include <ros/ros.h>

#include <algorithm>
#include <memory>

namespace {

using ehc_common::kLogThrottle;
constexpr double kMaxServeWait = 0.002;  ///< s the loop blocks on the Water2 socket per turn

class HardwareStandInNode {
 public:
  HardwareStandInNode(ros::NodeHandle& nh, const ehc_common::NodeParams& params)
      : setup_(params, "ehc_hardware_standin_node") {
    const int port = params.getInRange("port", 0, 0, 65535);  // 0: a free port
    ros::param::del("~water2_port");  // an earlier run's: never read as this run's port
    const ehc_control::RobotConfig& robot = setup_.robot;
    world_ = std::make_unique<ehc_sim::SimWorld>(setup_.cfg, robot, setup_.scene);
    stand_in_ = std::make_unique<ehc_sim::HardwareStandIn>(*world_);
    camera_ = std::make_unique<ehc_sim::SimCameraStreams>(nh, setup_, *world_);
    gate_ = std::make_unique<ehc_sim::CommandGate>(robot);  // /sim/status command fields: none here
    server_ = std::make_unique<ehc_sim::Water2ApiServer>(port);
    ros::param::set("~water2_port", server_->port());  // an output: the port it got
    ROS_INFO("[ehc_hardware_standin_node] Water2 API on 127.0.0.1:%d; rm_driver topics /rm_driver/*",
             server_->port());

    joint_pub_ = nh.advertise<sensor_msgs::JointState>("/joint_states", 10);
    objects_pub_ = nh.advertise<ehc_msgs::SimObjectPoses>("/sim/object_poses", 10);
    status_pub_ = nh.advertise<ehc_msgs::SimStatus>("/sim/status", 10);
    base_truth_pub_ = nh.advertise<nav_msgs::Odometry>("/sim/base_pose", 10);
    tcp_truth_pub_ = nh.advertise<geometry_msgs::PoseStamped>("/sim/tcp_pose", 10);
    const ros::TransportHints fast = ros::TransportHints().tcpNoDelay();
    subs_.push_back(nh.subscribe("/rm_driver/JointPos", 100, &HardwareStandInNode::onJointPos, this, fast));
    subs_.push_back(nh.subscribe("/rm_driver/Emergency_Stop", 10, &HardwareStandInNode::onStop, this));
    subs_.push_back(nh.subscribe("/rm_driver/Gripper_Set", 10, &HardwareStandInNode::onGripperSet, this));
    subs_.push_back(nh.subscribe("/rm_driver/Gripper_Pick", 10, &HardwareStandInNode::onGripperPick, this));
  }

  void run() {
    stand_in_->advanceTo(ros::WallTime::now().toSec());
    publish();
    while (ros::ok()) {
      ros::spinOnce();
      server_->serve(
          kMaxServeWait, [this](double v, double w) { stand_in_->onJoyControl(v, w); },
          [this] { return stand_in_->statusPose(); });
      const long skipped = stand_in_->counters().skipped_steps;
      if (stand_in_->advanceTo(ros::WallTime::now().toSec()) > 0) {
        reportCollisions();
        publish();
      }
      if (stand_in_->counters().skipped_steps > skipped)
        ROS_WARN_THROTTLE(kLogThrottle, "[ehc_hardware_standin_node] stalled: %ld steps skipped so far (world time lags "
                                        "the wall clock)", stand_in_->counters().skipped_steps);
    }
  }

 private:
  void onJointPos(const rm_msgs::JointPos::ConstPtr& m) {
    const std::string why = stand_in_->onJointPos(std::vector<double>(m->joint.begin(), m->joint.end()));
    if (!why.empty())
      ROS_WARN_STREAM_THROTTLE(kLogThrottle, "[ehc_hardware_standin_node] rm_driver ignores a frame: "
                                                 << why << " (" << stand_in_->counters().frames_ignored << " so far)");
  }
  void onStop(const rm_msgs::Stop::ConstPtr& m) {
    if (!m->state) return;
    stand_in_->onEmergencyStop();
    ROS_WARN("[ehc_hardware_standin_node] rm_driver: emergency stop, the arm holds");
  }
  void onGripperSet(const rm_msgs::Gripper_Set::ConstPtr& m) { stand_in_->onGripperSet(m->position); }
  void onGripperPick(const rm_msgs::Gripper_Pick::ConstPtr&) { stand_in_->onGripperPick(); }

  void reportCollisions() {
    const ehc_sim::StepReport& r = world_->lastStep();
    if (r.robot_world_collision || r.self_collision)
      ROS_WARN_STREAM_THROTTLE(kLogThrottle, "[ehc_hardware_standin_node] collision: " << r.collisions.front().a << " | "
                                                                               << r.collisions.front().b);
  }

  /// The hardware's messages, stamped with the wall clock at publication (as the drivers do).
  void publish() {
    const ros::Time stamp = ros::Time::now();
    const std::int64_t t_ns = world_->timeNs();
    camera_->publishDue(*world_, t_ns, stamp);
    sensor_msgs::JointState js;
    ehc_sim::fillJointState(world_->robot(), stamp, &js);
    joint_pub_.publish(js);
    ehc_msgs::SimObjectPoses objects;
    ehc_sim::fillObjectPoses(*world_, stamp, &objects);
    objects_pub_.publish(objects);
    ehc_msgs::SimStatus status;
    ehc_sim::fillStatus(*world_, *gate_, false, stamp, &status);
    status_pub_.publish(status);
    nav_msgs::Odometry base;
    ehc_sim::fillTrueBase(world_->robot(), stamp, &base);
    base_truth_pub_.publish(base);
    geometry_msgs::PoseStamped tcp;
    tcp.header = base.header;
    tcp.pose = ehc_sim::toPose(world_->linkPose(world_->robot().robot().tcp_frame));
    tcp_truth_pub_.publish(tcp);
  }

  ehc_sim::BulletNodeSetup setup_;
  std::unique_ptr<ehc_sim::SimWorld> world_;
  std::unique_ptr<ehc_sim::HardwareStandIn> stand_in_;
  std::unique_ptr<ehc_sim::SimCameraStreams> camera_;  ///< camera rates on the world's time
  std::unique_ptr<ehc_sim::CommandGate> gate_;
  std::unique_ptr<ehc_sim::Water2ApiServer> server_;
  ros::Publisher joint_pub_, objects_pub_, status_pub_, base_truth_pub_, tcp_truth_pub_;
  std::vector<ros::Subscriber> subs_;
};

}  // namespace

int main(int argc, char** argv) {
  return ehc_common::runNode(argc, argv, "ehc_hardware_standin_node", 1, [](const ehc_common::NodeParams& params, ros::NodeHandle& nh) {
    HardwareStandInNode node(nh, params);
    params.has("water2_port");  // its own output, left by an earlier run: not an input
    ehc_common::checkNodeParams(params);
    node.run();
    return 0;
  });
}
