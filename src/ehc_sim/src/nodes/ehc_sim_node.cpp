// ehc_sim_node: the Bullet-backed fake robot (ROS wrapper of ehc_sim::SimWorld,
// SimulatedCamera and CommandGate).
//
//   rosrun ehc_sim ehc_sim_node _config:=config/sim/bullet_sim.yaml
//       [_scene:=config/scenes/table_three_objects.yaml] [_free_run:=true] [_seed:=N]
//
// Lock-step (default): publishes /clock and the state stamped t, waits for the
// JointVelocityCommand stamped t and a /cmd_vel received since the last step, then advances
// one step of sim.dt. Free-run: steps every sim.dt of wall time with the latest commands
// (zeroed after sim.command_timeout without a fresh one). Sim time starts at 1 s.
//
// Publishes /clock, /joint_states, /odom, /tf (odom -> base_link and every URDF link),
// /camera/color/image_raw (mono8) + /camera/color/camera_info, /camera/depth/points,
// /sim/object_poses (ground truth, metrics only), /sim/status.
// Subscribes /cmd_vel, /arm/joint_velocity_cmd. Services /sim/reset (ehc_msgs/ResetScene),
// /sim/gripper (std_srvs/SetBool: true = close, false = open).

#include "sim_ros_conversions.h"

#include "ehc_msgs/JointVelocityCommand.h"
#include "ehc_msgs/ResetScene.h"

#include <geometry_msgs/Twist.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <std_srvs/SetBool.h>
#include <tf2_msgs/TFMessage.h>

#include <memory>

namespace {

class SimNode {
 public:
  SimNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : nh_(nh) {
    std::string config_file;
    if (!pnh.getParam("config", config_file))
      throw std::invalid_argument("[ehc_sim_node] parameter _config:=<sim.yaml> is required");
    cfg_ = ehc_sim::loadSimConfig(config_file);
    std::string scene_file = cfg_.scene_file;
    pnh.param("scene", scene_file, scene_file);
    if (scene_file.empty()) throw std::invalid_argument("[ehc_sim_node] no scene: set sim.scene or _scene:=");
    pnh.param("free_run", cfg_.free_run, cfg_.free_run);
    int seed = static_cast<int>(cfg_.seed);
    pnh.param("seed", seed, seed);
    if (seed < 0) throw std::invalid_argument("[ehc_sim_node] _seed must be >= 0");
    cfg_.seed = static_cast<unsigned>(seed);
    const ehc_control::RobotConfig robot = ehc_control::loadRobotConfig(cfg_.robot_file);
    const ehc_sim::SceneConfig scene = ehc_sim::loadSceneConfig(scene_file);
    const ehc_control::PinholeCamera intrinsics = ehc_control::loadPinholeCamera(cfg_.camera_file);
    ROS_INFO_STREAM("[ehc_sim_node] start-up configuration\n"
                    << cfg_.summary() << robot.summary() << "\n"
                    << scene.summary());

    world_ = std::make_unique<ehc_sim::SimWorld>(cfg_, robot, scene);
    camera_ = std::make_unique<ehc_sim::SimulatedCamera>(intrinsics, cfg_.camera, cfg_.seed);
    camera_->setScene(world_->bodies(), scene.floor_shade);
    gate_ = std::make_unique<ehc_sim::CommandGate>(robot);
    camera_frame_ = robot.camera_frame;

    nh_.setCallbackQueue(&queue_);
    const ros::TransportHints fast = ros::TransportHints().tcpNoDelay();
    clock_pub_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 10);
    joint_pub_ = nh_.advertise<sensor_msgs::JointState>("/joint_states", 10);
    odom_pub_ = nh_.advertise<nav_msgs::Odometry>("/odom", 10);
    tf_pub_ = nh_.advertise<tf2_msgs::TFMessage>("/tf", 100);
    image_pub_ = nh_.advertise<sensor_msgs::Image>("/camera/color/image_raw", 2);
    info_pub_ = nh_.advertise<sensor_msgs::CameraInfo>("/camera/color/camera_info", 2);
    cloud_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("/camera/depth/points", 2);
    objects_pub_ = nh_.advertise<ehc_msgs::SimObjectPoses>("/sim/object_poses", 10);
    status_pub_ = nh_.advertise<ehc_msgs::SimStatus>("/sim/status", 10);
    cmd_vel_sub_ = nh_.subscribe("/cmd_vel", 10, &SimNode::onCmdVel, this, fast);
    arm_sub_ = nh_.subscribe("/arm/joint_velocity_cmd", 10, &SimNode::onArmCommand, this, fast);
    reset_srv_ = nh_.advertiseService("/sim/reset", &SimNode::onReset, this);
    gripper_srv_ = nh_.advertiseService("/sim/gripper", &SimNode::onGripper, this);
  }

  void run() {
    publishState(true);
    ros::WallTime next_step = ros::WallTime::now() + ros::WallDuration(cfg_.dt);
    while (ros::ok()) {
      queue_.callAvailable(ros::WallDuration(cfg_.free_run ? 0.0005 : 0.002));
      const ros::WallTime now = ros::WallTime::now();
      if (!cfg_.free_run) {
        if (gate_->ready()) {
          step();
        } else if (!answered_ && (now - last_publish_).toSec() > cfg_.state_republish_period) {
          publishState(false);  // nobody answered (controller not up yet): send it again
        }
      } else if (now >= next_step) {
        if ((now - last_base_cmd_).toSec() > cfg_.command_timeout ||
            (now - last_arm_cmd_).toSec() > cfg_.command_timeout)
          gate_->zero();
        step();
        next_step += ros::WallDuration(cfg_.dt);
        if (next_step < now) next_step = now;  // do not try to catch up after a stall
      }
    }
  }

 private:
  void step() {
    const ehc_sim::StepReport& r = world_->step(gate_->command());
    if (r.robot_world_collision || r.self_collision)
      ROS_WARN_STREAM_THROTTLE(1.0, "[ehc_sim_node] collision: " << r.collisions.front().a << " | "
                                                                   << r.collisions.front().b);
    publishState(true);
  }

  /// Publishes /clock, the camera (when due), the state and the status for the current time.
  void publishState(bool fresh) {
    const std::int64_t t_ns = world_->timeNs();
    const ros::Time stamp = ehc_sim::rosStamp(t_ns);
    rosgraph_msgs::Clock clock;
    clock.clock = stamp;
    clock_pub_.publish(clock);
    if (fresh) {
      gate_->newState(static_cast<std::int64_t>(stamp.toNSec()));
      answered_ = false;
      publishCamera(t_ns, stamp);
    }
    sensor_msgs::JointState js;
    ehc_sim::fillJointState(*world_, stamp, &js);
    nav_msgs::Odometry odom;
    ehc_sim::fillOdometry(*world_, stamp, &odom);
    tf2_msgs::TFMessage tf;
    ehc_sim::fillTransforms(*world_, stamp, &tf.transforms);
    tf_pub_.publish(tf);
    odom_pub_.publish(odom);
    ehc_msgs::SimObjectPoses objects;
    ehc_sim::fillObjectPoses(*world_, stamp, &objects);
    objects_pub_.publish(objects);
    ehc_msgs::SimStatus status;
    ehc_sim::fillStatus(*world_, *gate_, !cfg_.free_run, stamp, &status);
    status_pub_.publish(status);
    joint_pub_.publish(js);  // last: the controller answers this one
    last_publish_ = ros::WallTime::now();
  }

  void publishCamera(std::int64_t t_ns, const ros::Time& stamp) {
    auto due = [&](double rate, std::int64_t* next) {
      if (rate <= 0.0 || t_ns < *next) return false;
      const auto period = static_cast<std::int64_t>(std::llround(1e9 / rate));
      *next = (t_ns / period + 1) * period;
      return true;
    };
    if (due(cfg_.camera.image_rate, &next_image_ns_)) {
      camera_->render(*world_, &image_);
      sensor_msgs::Image img;
      ehc_sim::fillImage(image_, camera_frame_, stamp, &img);
      sensor_msgs::CameraInfo info;
      ehc_sim::fillCameraInfo(camera_->intrinsics(), camera_frame_, stamp, &info);
      image_pub_.publish(img);
      info_pub_.publish(info);
    }
    if (due(cfg_.camera.cloud_rate, &next_cloud_ns_)) {
      camera_->cloud(*world_, &points_);
      sensor_msgs::PointCloud2 cloud;
      ehc_sim::fillCloud(points_, camera_frame_, stamp, &cloud);
      cloud_pub_.publish(cloud);
    }
  }

  void onCmdVel(const geometry_msgs::Twist::ConstPtr& m) {
    const std::string why = gate_->onBaseTwist(m->linear.x, m->linear.y, m->angular.z);
    answered_ = true;
    last_base_cmd_ = ros::WallTime::now();
    if (!why.empty())
      ROS_WARN_STREAM_THROTTLE(1.0, "[ehc_sim_node] /cmd_vel rejected (base stopped): " << why << " ("
                                        << gate_->counters().base_rejected << " rejected so far)");
  }

  void onArmCommand(const ehc_msgs::JointVelocityCommand::ConstPtr& m) {
    const std::string why = gate_->onArmCommand(static_cast<std::int64_t>(m->header.stamp.toNSec()),
                                                m->names, m->velocities, !cfg_.free_run);
    answered_ = true;
    if (why.empty()) last_arm_cmd_ = ros::WallTime::now();
    if (!why.empty())
      ROS_WARN_STREAM_THROTTLE(1.0, "[ehc_sim_node] /arm/joint_velocity_cmd rejected: " << why << " ("
                                        << gate_->counters().arm_rejected << " rejected, "
                                        << gate_->counters().arm_stale << " stale so far)");
  }

  bool onReset(ehc_msgs::ResetScene::Request& req, ehc_msgs::ResetScene::Response& res) {
    try {
      if (!req.scene_file.empty()) {
        const ehc_sim::SceneConfig scene = ehc_sim::loadSceneConfig(req.scene_file);
        world_->setScene(scene, req.seed);
        camera_->setScene(world_->bodies(), scene.floor_shade);
      } else {
        world_->reset(req.seed);
      }
      camera_->reseed(req.seed);
      gate_->zero();
      gate_->resetCounters();
      next_image_ns_ = next_cloud_ns_ = 0;
      res.success = true;
      res.message = "scene '" + world_->scene().name + "' reset with seed " + std::to_string(req.seed);
      ROS_INFO_STREAM("[ehc_sim_node] " << res.message);
      publishState(true);
    } catch (const std::exception& e) {
      res.success = false;
      res.message = e.what();
      ROS_ERROR_STREAM("[ehc_sim_node] reset failed, scene unchanged: " << e.what());
    }
    return true;
  }

  bool onGripper(std_srvs::SetBool::Request& req, std_srvs::SetBool::Response& res) {
    world_->commandGripper(req.data);
    res.success = true;
    res.message = std::string(req.data ? "closing" : "opening") + " (state " +
                  ehc_sim::toString(world_->gripper().state()) + ")";
    return true;
  }

  ros::NodeHandle nh_;
  ros::CallbackQueue queue_;
  ehc_sim::SimConfig cfg_;
  std::unique_ptr<ehc_sim::SimWorld> world_;
  std::unique_ptr<ehc_sim::SimulatedCamera> camera_;
  std::unique_ptr<ehc_sim::CommandGate> gate_;
  std::string camera_frame_;
  vpImage<unsigned char> image_;
  std::vector<Eigen::Vector3f> points_;
  std::int64_t next_image_ns_ = 0, next_cloud_ns_ = 0;
  bool answered_ = false;
  ros::WallTime last_publish_, last_base_cmd_, last_arm_cmd_;
  ros::Publisher clock_pub_, joint_pub_, odom_pub_, tf_pub_, image_pub_, info_pub_, cloud_pub_,
      objects_pub_, status_pub_;
  ros::Subscriber cmd_vel_sub_, arm_sub_;
  ros::ServiceServer reset_srv_, gripper_srv_;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "ehc_sim_node");
  ros::NodeHandle nh, pnh("~");
  try {
    SimNode node(nh, pnh);
    node.run();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM(e.what());
    return 1;
  }
  return 0;
}
