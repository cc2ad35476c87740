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
//
// _port 0 (default): an ephemeral port; the port in use is set as the private parameter
// ~water2_port (read it before pointing the bridge at it: WATER2_PORT=... run_realman.sh).
// As the rm_driver: subscribes /rm_driver/JointPos, /rm_driver/Emergency_Stop,
// /rm_driver/Gripper_Set, /rm_driver/Gripper_Pick; publishes /joint_states (joint1..joint6).
// As the D435 driver: /camera/color/image_raw (mono8), /camera/color/camera_info,
// /camera/depth/points. As the simulator (metrics and the sequencer's grasp result only):
// /sim/status, /sim/object_poses. Not published here (the real nodes do it): /odom, /tf.

#include "sim_ros_conversions.h"

#include "ehc_sim/hardware_stand_in.h"
#include "ehc_sim/water2_api_server.h"

#include <rm_msgs/Gripper_Pick.h>
#include <rm_msgs/Gripper_Set.h>
#include <rm_msgs/JointPos.h>
#include <rm_msgs/Stop.h>
#include <ros/ros.h>

#include <algorithm>
#include <memory>

namespace {

constexpr double kLogThrottle = 1.0;  ///< s between repeats of a throttled log message
constexpr double kMaxServeWait = 0.002;  ///< s the loop blocks on the Water2 socket per turn

class HardwareStandInNode {
 public:
  HardwareStandInNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
    std::string config_file;
    if (!pnh.getParam("config", config_file))
      throw std::invalid_argument("[ehc_hardware_standin_node] parameter _config:=<sim.yaml> is required");
    cfg_ = ehc_sim::loadSimConfig(config_file);
    std::string scene_file = cfg_.scene_file;
    pnh.param("scene", scene_file, scene_file);
    if (scene_file.empty()) throw std::invalid_argument("[ehc_hardware_standin_node] no scene: set sim.scene or _scene:=");
    int seed = static_cast<int>(cfg_.fake_robot.seed);
    pnh.param("seed", seed, seed);
    if (seed < 0) throw std::invalid_argument("[ehc_hardware_standin_node] _seed must be >= 0");
    cfg_.fake_robot.seed = static_cast<unsigned>(seed);
    int port = 0;
    pnh.param("port", port, port);
    const ehc_control::RobotConfig robot = ehc_control::loadRobotConfig(cfg_.fake_robot.robot_file);
    const ehc_sim::SceneConfig scene = ehc_sim::loadSceneConfig(scene_file);
    const ehc_control::PinholeCamera intrinsics = ehc_control::loadPinholeCamera(cfg_.camera_file);
    ROS_INFO_STREAM("[ehc_hardware_standin_node] start-up configuration\n"
                    << cfg_.summary() << robot.summary() << "\n" << scene.summary());

    world_ = std::make_unique<ehc_sim::SimWorld>(cfg_, robot, scene);
    stand_in_ = std::make_unique<ehc_sim::HardwareStandIn>(*world_);
    camera_ = std::make_unique<ehc_sim::SimulatedCamera>(intrinsics, cfg_.camera, cfg_.fake_robot.seed);
    camera_->setScene(world_->bodies(), scene.floor_shade);
    camera_frame_ = robot.camera_frame;
    image_clock_ = ehc_sim::StreamClock(cfg_.camera.image_rate);
    cloud_clock_ = ehc_sim::StreamClock(cfg_.camera.cloud_rate);
    gate_ = std::make_unique<ehc_sim::CommandGate>(robot);  // /sim/status command fields: none here
    server_ = std::make_unique<ehc_sim::Water2ApiServer>(port);
    pnh.setParam("water2_port", server_->port());
    ROS_INFO("[ehc_hardware_standin_node] Water2 API on 127.0.0.1:%d; rm_driver topics /rm_driver/*",
             server_->port());

    joint_pub_ = nh.advertise<sensor_msgs::JointState>("/joint_states", 10);
    image_pub_ = nh.advertise<sensor_msgs::Image>("/camera/color/image_raw", 2);
    info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("/camera/color/camera_info", 2);
    cloud_pub_ = nh.advertise<sensor_msgs::PointCloud2>("/camera/depth/points", 2);
    objects_pub_ = nh.advertise<ehc_msgs::SimObjectPoses>("/sim/object_poses", 10);
    status_pub_ = nh.advertise<ehc_msgs::SimStatus>("/sim/status", 10);
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
    if (image_clock_.due(t_ns)) {
      camera_->render(*world_, &image_);
      sensor_msgs::Image img;
      ehc_sim::fillImage(image_, camera_frame_, stamp, &img);
      sensor_msgs::CameraInfo info;
      ehc_sim::fillCameraInfo(camera_->intrinsics(), camera_frame_, stamp, &info);
      image_pub_.publish(img);
      info_pub_.publish(info);
    }
    if (cloud_clock_.due(t_ns)) {
      camera_->cloud(*world_, &points_);
      sensor_msgs::PointCloud2 cloud;
      ehc_sim::fillCloud(points_, camera_frame_, stamp, &cloud);
      cloud_pub_.publish(cloud);
    }
    sensor_msgs::JointState js;
    ehc_sim::fillJointState(world_->robot(), stamp, &js);
    joint_pub_.publish(js);
    ehc_msgs::SimObjectPoses objects;
    ehc_sim::fillObjectPoses(*world_, stamp, &objects);
    objects_pub_.publish(objects);
    ehc_msgs::SimStatus status;
    ehc_sim::fillStatus(*world_, *gate_, false, stamp, &status);
    status_pub_.publish(status);
  }

  ehc_sim::SimConfig cfg_;
  std::unique_ptr<ehc_sim::SimWorld> world_;
  std::unique_ptr<ehc_sim::HardwareStandIn> stand_in_;
  std::unique_ptr<ehc_sim::SimulatedCamera> camera_;
  std::unique_ptr<ehc_sim::CommandGate> gate_;
  std::unique_ptr<ehc_sim::Water2ApiServer> server_;
  std::string camera_frame_;
  vpImage<unsigned char> image_;
  std::vector<Eigen::Vector3f> points_;
  ehc_sim::StreamClock image_clock_, cloud_clock_;  ///< camera rates on the world's time
  ros::Publisher joint_pub_, image_pub_, info_pub_, cloud_pub_, objects_pub_, status_pub_;
  std::vector<ros::Subscriber> subs_;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "ehc_hardware_standin_node");
  ros::NodeHandle nh, pnh("~");
  try {
    HardwareStandInNode node(nh, pnh);
    node.run();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM(e.what());
    return 1;
  }
  return 0;
}
