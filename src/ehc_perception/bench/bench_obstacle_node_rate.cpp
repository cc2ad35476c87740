// bench_obstacle_node_rate: the rate of /ehc/obstacles under a depth stream (docs/DESIGN.md,
// performance bars). A ROS node that plays the camera and the robot for a running
// ehc_obstacle_node (bench/obstacle_node_rate.sh starts master, node and this): organised
// `width` x `height` XYZ+RGB clouds (640x480: 4.9 MB each, a full D435 frame; 1920x1080: 2 M
// points, 33 MB; a wall 2 m ahead, a table edge 1.2 m ahead in the lower part, 10 % invalid
// pixels as NaN) at `cloud_hz`, /joint_states and /odom at 100 Hz, a static tf odom -> camera.
// After `warmup` s it counts /ehc/obstacles for `seconds` s and prints one JSON line
// (perception.obstacle_node_rate_<width>x<height>): both rates and the largest gap. Wall-clock
// figures: noisy on a shared machine.
//   rosrun ehc_perception bench_obstacle_node_rate [_cloud_hz:=30] [_seconds:=20] [_warmup:=5]
//       [_width:=640] [_height:=480]
#include "ehc_common/bench_util.h"
#include "ehc_msgs/ObstacleArray.h"

#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

namespace {

sensor_msgs::PointCloud2 depthCloud(const std::string& frame, int w, int h) {
  const float f = 615.0f * static_cast<float>(w) / 640.0f;  // the D435's field of view at any size
  sensor_msgs::PointCloud2 m;
  m.header.frame_id = frame;
  m.height = h;
  m.width = w;
  const char* names[] = {"x", "y", "z", "rgb"};
  for (int i = 0; i < 4; ++i) {
    sensor_msgs::PointField pf;
    pf.name = names[i];
    pf.offset = 4 * i;
    pf.datatype = sensor_msgs::PointField::FLOAT32;
    pf.count = 1;
    m.fields.push_back(pf);
  }
  m.point_step = 16;
  m.row_step = 16 * w;
  m.is_dense = false;
  m.data.resize(static_cast<std::size_t>(m.row_step) * h);
  std::mt19937 rng(0);
  std::uniform_real_distribution<float> uni(0.0f, 1.0f);
  const std::uint32_t grey = 0x00808080;
  float rgb;
  std::memcpy(&rgb, &grey, 4);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      float depth = (v >= h * 5 / 8 && u >= w * 5 / 32 && u < w * 27 / 32) ? 1.2f : 2.0f;
      if (uni(rng) < 0.1f) depth = std::nanf("");
      // Optical frame: x right, y down, z ahead.
      const float p[4] = {(u - 0.5f * w) / f * depth, (v - 0.5f * h) / f * depth, depth, rgb};
      std::memcpy(&m.data[static_cast<std::size_t>(v) * m.row_step + 16 * u], p, 16);
    }
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "bench_obstacle_node_rate");
  ros::NodeHandle nh, pnh("~");
  const double cloud_hz = pnh.param("cloud_hz", 30.0), seconds = pnh.param("seconds", 20.0),
               warmup = pnh.param("warmup", 5.0);
  const int width = pnh.param("width", 640), height = pnh.param("height", 480);
  ros::Publisher cloud_pub = nh.advertise<sensor_msgs::PointCloud2>("/camera/depth/points", 1);
  ros::Publisher js_pub = nh.advertise<sensor_msgs::JointState>("/joint_states", 5);
  ros::Publisher odom_pub = nh.advertise<nav_msgs::Odometry>("/odom", 5);
  std::vector<double> received;
  ros::Subscriber sub = nh.subscribe<ehc_msgs::ObstacleArray>(
      "/ehc/obstacles", 100, [&](const ehc_msgs::ObstacleArrayConstPtr&) { received.push_back(ros::WallTime::now().toSec()); });
  tf2_ros::StaticTransformBroadcaster static_tf;
  geometry_msgs::TransformStamped t;
  t.header.stamp = ros::Time::now();
  t.header.frame_id = "odom";
  t.child_frame_id = "bench_camera_optical";
  t.transform.translation.x = 0.3;
  t.transform.translation.z = 1.0;
  // optical (z ahead, x right, y down) -> odom (x ahead, y left, z up)
  t.transform.rotation.x = -0.5;
  t.transform.rotation.y = 0.5;
  t.transform.rotation.z = -0.5;
  t.transform.rotation.w = 0.5;
  static_tf.sendTransform(t);
  sensor_msgs::PointCloud2 cloud = depthCloud("bench_camera_optical", width, height);
  sensor_msgs::JointState js;
  js.name = {"joint1", "joint2", "joint3", "joint4", "joint5", "joint6"};
  js.position = {0.0, 0.5, -1.9, 0.0, -0.5, 0.0};
  nav_msgs::Odometry odom;
  odom.header.frame_id = "odom";
  odom.pose.pose.orientation.w = 1.0;
  ros::WallDuration(2.0).sleep();  // connections

  const double start = ros::WallTime::now().toSec();
  double next_cloud = start, next_state = start;
  int clouds_measured = 0;
  while (ros::ok() && ros::WallTime::now().toSec() - start < warmup + seconds) {
    const double now = ros::WallTime::now().toSec();
    if (now >= next_state) {
      js.header.stamp = odom.header.stamp = ros::Time::now();
      js_pub.publish(js);
      odom_pub.publish(odom);
      next_state += 0.01;
    }
    if (now >= next_cloud) {
      cloud.header.stamp = ros::Time::now();
      cloud_pub.publish(cloud);
      if (now - start >= warmup) ++clouds_measured;
      next_cloud += 1.0 / cloud_hz;
    }
    ros::spinOnce();
    ros::WallDuration(0.0005).sleep();
  }
  const double t0 = start + warmup;
  std::vector<double> kept;
  for (double s : received)
    if (s >= t0) kept.push_back(s);
  double gap = 0.0;
  for (std::size_t i = 1; i < kept.size(); ++i) gap = std::max(gap, kept[i] - kept[i - 1]);
  ehc_common::benchPrintValues(
      "perception.obstacle_node_rate_" + std::to_string(width) + "x" + std::to_string(height),
      {{"points", width * height},
       {"clouds_hz", ehc_common::jsonNumber(clouds_measured / seconds)},
       {"obstacles_hz", ehc_common::jsonNumber(kept.size() / seconds)},
       {"seconds", seconds},
       {"max_gap_ms", ehc_common::jsonNumber(1e3 * gap)}});
  return 0;
}
