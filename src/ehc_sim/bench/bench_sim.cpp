// bench_sim: simulator speed (issue bars: physics + state publication >= 1 kHz; image + cloud
// >= 30 Hz at 640x480 / 80x60 rays). One JSON object per line (ehc_common/bench_util.h).
// "State publication" = filling and serialising /joint_states, /odom, /tf, /sim/object_poses
// and /sim/status (what the node does per step, minus the socket write).

#include "sim_ros_conversions.h"

#include "ehc_common/bench_util.h"

#include <ros/serialization.h>
#include <tf2_msgs/TFMessage.h>

#include <cmath>
#include <cstdio>

namespace {

template <class M>
std::size_t serialise(const M& m, std::vector<uint8_t>* buf) {
  const uint32_t n = ros::serialization::serializationLength(m);
  buf->resize(n);
  ros::serialization::OStream s(buf->data(), n);
  ros::serialization::serialize(s, m);
  return n;
}

/// One JSON line {"bench": name, "rate_hz", "bar_hz", "meets_bar"}.
void printRate(const std::string& name, double mean_us, double bar_hz) {
  ehc_common::benchPrintValues(name, {{"rate_hz", ehc_common::jsonNumber(1e6 / mean_us)},
                                      {"bar_hz", bar_hz},
                                      {"meets_bar", 1e6 / mean_us >= bar_hz}});
}

}  // namespace

int main() {
  using namespace ehc_sim;
  const SimConfig cfg = loadSimConfig(EHC_SIM_CONFIG);
  const ehc_control::RobotConfig robot = ehc_control::loadRobotConfig(cfg.fake_robot.robot_file);
  const std::string scenes = std::string(EHC_CONFIG_DIR) + "/scenes/";
  SimWorld world(cfg, robot, loadSceneConfig(scenes + "table_three_objects.yaml"));
  CommandGate gate(robot);
  Eigen::VectorXd cmd = Eigen::VectorXd::Zero(world.robot().nDof());
  auto command = [&](int i) {
    cmd[0] = 0.2 + 0.1 * std::sin(0.01 * i);
    cmd[1] = 0.2 * std::cos(0.013 * i);
    for (int j = 2; j < cmd.size(); ++j) cmd[j] = 0.3 * std::sin(0.02 * i + j);
    return cmd;
  };
  const int n = 5000;
  const ehc_common::Json setting = {{"scene", "table_three_objects"},
                                    {"dt", ehc_common::jsonNumber(cfg.fake_robot.dt)},
                                    {"substeps", cfg.substeps()}};

  ehc_common::benchReport("sim_physics_step", n, [&](int i) { world.step(command(i)); }, setting);

  world.reset(1);
  std::vector<uint8_t> buf;
  sensor_msgs::JointState js;
  nav_msgs::Odometry odom;
  tf2_msgs::TFMessage tf;
  ehc_msgs::SimObjectPoses objects;
  ehc_msgs::SimStatus status;
  const auto s = ehc_common::benchReport(
      "sim_step_and_state_publication", n,
      [&](int i) {
        world.step(command(i));
        const ros::Time stamp = rosStamp(world.timeNs());
        fillJointState(world.robot(), stamp, &js);
        fillOdometry(world.robot(), stamp, &odom);
        fillTransforms(world, stamp, &tf.transforms);
        fillObjectPoses(world, stamp, &objects);
        fillStatus(world, gate, true, stamp, &status);
        serialise(js, &buf);
        serialise(odom, &buf);
        serialise(tf, &buf);
        serialise(objects, &buf);
        serialise(status, &buf);
      },
      setting);
  printRate("sim_step_and_state_publication_rate", s.mean_us, 1000);

  // Camera: ready pose in front of the table (three tags in view), 640x480, 80x60 depth samples.
  world.reset(1);
  SimulatedCamera camera(ehc_control::loadPinholeCamera(simCameraFile(cfg, robot)), cfg.camera, 1);
  camera.setScene(world.bodies(), world.scene().floor_shade);
  vpImage<unsigned char> image;
  std::vector<Eigen::Vector3f> points;
  const int m = 200;
  const ehc_common::Json cam_setting = {
      {"width", 640},
      {"height", 480},
      {"rays", std::to_string(cfg.camera.ray_cols) + "x" + std::to_string(cfg.camera.ray_rows)},
      {"faces", camera.faceCount()}};
  ehc_common::Json cloud_setting = cam_setting;
  ehc_common::benchReport("sim_image_render", m, [&](int) { camera.render(world, &image); }, cam_setting);
  camera.cloud(world, &points);
  cloud_setting["points"] = points.size();
  ehc_common::benchReport("sim_cloud_raster", m, [&](int) { camera.cloud(world, &points); }, cloud_setting);
  sensor_msgs::Image img;
  sensor_msgs::PointCloud2 cloud;
  const auto c = ehc_common::benchReport(
      "sim_image_and_cloud", m,
      [&](int) {
        const ros::Time stamp = rosStamp(world.timeNs());
        camera.render(world, &image);
        camera.cloud(world, &points);
        fillImage(image, "camera_color_optical_frame", stamp, &img);
        fillCloud(points, "camera_color_optical_frame", stamp, &cloud);
        serialise(img, &buf);
        serialise(cloud, &buf);
      },
      cam_setting);
  printRate("sim_image_and_cloud_rate", c.mean_us, 30);
  return 0;
}
