#pragma once
// The start-up and the simulated D435 streams shared by both Bullet nodes (ehc_sim_node, the
// lock-step simulator, and ehc_hardware_standin_node, the hardware stand-in of the deployment
// rehearsal). Header-only; the logic is the cores' (SimWorld, SimulatedCamera, StreamClock).

#include "lock_step_node.h"
#include "sim_ros_conversions.h"

#include <ros/ros.h>

#include <memory>
#include <functional>
#include <string>

namespace ehc_sim {

/// What a Bullet node loads at start-up: _config (required), _scene (overrides sim.scene),
/// _free_run / _seed (applyNodeOverrides); the configuration is printed once.
struct BulletNodeSetup {
  SimConfig cfg;
  ehc_control::RobotConfig robot;
  SceneConfig scene;
  ehc_control::PinholeCamera intrinsics;

  BulletNodeSetup(const ehc_common::NodeParams& params, const std::string& node) {
    cfg = loadSimConfig(params.requireText("config", "<sim.yaml>"));
    const std::string scene_file = params.get<std::string>("scene", cfg.scene_file);
    if (scene_file.empty()) throw std::invalid_argument("[" + node + "] no scene: set sim.scene or _scene:=");
    applyNodeOverrides(params, &cfg.fake_robot);
    robot = ehc_control::loadRobotConfig(cfg.fake_robot.robot_file);
    scene = loadSceneConfig(scene_file);
    intrinsics = ehc_control::loadPinholeCamera(simCameraFile(cfg, robot));
    ROS_INFO_STREAM("[" << node << "] start-up configuration\n"
                        << cfg.summary() << robot.summary() << "\n" << scene.summary());
  }
};

/// /camera/color/image_raw (mono8) + /camera/color/camera_info and /camera/depth/points, each
/// at its configured rate (camera.image_rate / cloud_rate) of the world's time.
class SimCameraStreams {
 public:
  SimCameraStreams(ros::NodeHandle& nh, const BulletNodeSetup& setup, const SimWorld& world)
      : camera_(setup.intrinsics, setup.cfg.camera, setup.cfg.fake_robot.seed),
        frame_(setup.robot.camera_frame),
        image_clock_(setup.cfg.camera.image_rate),
        cloud_clock_(setup.cfg.camera.cloud_rate) {
    camera_.setScene(world.bodies(), setup.scene.floor_shade);
    image_pub_ = nh.advertise<sensor_msgs::Image>("/camera/color/image_raw", 2);
    info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("/camera/color/camera_info", 2);
    cloud_pub_ = nh.advertise<sensor_msgs::PointCloud2>("/camera/depth/points", 2);
  }

  /// Renders and publishes what is due at the world's time `t_ns`, stamped `stamp`.
  /// `before_publish` (if set) runs just before an image or a cloud is published, with the
  /// frame's stamp in ns (the lock-step acknowledgement gate records the frame there, so an
  /// acknowledgement, which carries the stamp, can never arrive before the record).
  void publishDue(const SimWorld& world, std::int64_t t_ns, const ros::Time& stamp,
                  const std::function<void(AckStream, std::int64_t)>& before_publish = {}) {
    if (image_clock_.due(t_ns)) {
      camera_.render(world, &image_);
      sensor_msgs::Image img;
      fillImage(image_, frame_, stamp, &img);
      sensor_msgs::CameraInfo info;
      ehc_control::fillCameraInfo(camera_.intrinsics(), frame_, stamp, &info);  // an ideal pinhole
      if (before_publish) before_publish(AckStream::Image, static_cast<std::int64_t>(stamp.toNSec()));
      image_pub_.publish(img);
      info_pub_.publish(info);
    }
    if (cloud_clock_.due(t_ns)) {
      camera_.cloud(world, &points_);
      sensor_msgs::PointCloud2 cloud;
      fillCloud(points_, frame_, stamp, &cloud);
      if (before_publish) before_publish(AckStream::Cloud, static_cast<std::int64_t>(stamp.toNSec()));
      cloud_pub_.publish(cloud);
    }
  }

  /// After a scene reset (new bodies when the scene changed) with noise seed `seed`.
  void reset(const SimWorld& world, const SceneConfig* new_scene, unsigned seed) {
    if (new_scene) camera_.setScene(world.bodies(), new_scene->floor_shade);
    camera_.reseed(seed);
    image_clock_.reset();
    cloud_clock_.reset();
  }

 private:
  SimulatedCamera camera_;
  std::string frame_;
  StreamClock image_clock_, cloud_clock_;
  vpImage<unsigned char> image_;
  std::vector<Eigen::Vector3f> points_;
  ros::Publisher image_pub_, info_pub_, cloud_pub_;
};

}  // namespace ehc_sim
