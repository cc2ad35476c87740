// rostest: the three perception nodes with their shipped configs. This test publishes a
// static camera pose (tf), a rendered AprilTag image (rgb8) + camera_info, a table-scene depth
// cloud in the camera frame, and the robot state; it checks /ehc/target_pose,
// /ehc/grasp_candidates and /ehc/obstacles against the known geometry, that a NaN robot
// state stops the obstacle output, and that malformed clouds are rejected without harm.
#include "ehc_msgs/CloudTarget.h"
#include "ehc_msgs/GraspCandidates.h"
#include "ehc_msgs/TargetSelector.h"
#include "ehc_msgs/ObstacleArray.h"
#include "ehc_common/config_node.h"
#include "ehc_control/pinhole_camera.h"
#include "ehc_perception/tag_detector.h"
#include "ehc_perception/tag_image_renderer.h"
#include "ehc_test/perception_fixtures.h"

#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/JointState.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <std_msgs/Header.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <type_traits>

using namespace ehc_perception;
using namespace ehc_perception::test;

namespace {

const char* kCamFrame = "camera_color_optical_frame";

/// Camera 1.2 m above the floor at (0.3, 0), looking straight down (image x = world -y).
Eigen::Isometry3d worldFromCamera() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() << 0.3, 0.0, 1.2;
  T.linear().col(0) << 0, -1, 0;
  T.linear().col(1) << -1, 0, 0;
  T.linear().col(2) << 0, 0, -1;
  return T;
}

/// worldFromCamera() as the transform odom -> the camera's frame at `stamp`.
geometry_msgs::TransformStamped cameraPoseAt(const ros::Time& stamp) {
  geometry_msgs::TransformStamped tf = tf2::eigenToTransform(worldFromCamera());
  tf.header.frame_id = "odom";
  tf.child_frame_id = kCamFrame;
  tf.header.stamp = stamp;
  return tf;
}

const Eigen::Isometry3d kTagInCamera = facingTag(0.0, 0.0, 0.5, 0.2, -0.1, 0.3);
const double kTableZ = 0.58;

/// The points as a PointCloud2 in the camera frame: FLOAT32 x, y, z padded to 16 bytes (the
/// layout of PointCloud2Modifier's "xyz", which the simulated camera publishes) or FLOAT64.
template <class Scalar>
sensor_msgs::PointCloud2 xyzCloud(const PointList& pts) {
  static_assert(std::is_same<Scalar, float>::value || std::is_same<Scalar, double>::value);
  sensor_msgs::PointCloud2 c;
  c.header.frame_id = kCamFrame;
  sensor_msgs::PointCloud2Modifier mod(c);
  if (std::is_same<Scalar, float>::value) {
    mod.setPointCloud2FieldsByString(1, "xyz");
  } else {
    using sensor_msgs::PointField;
    mod.setPointCloud2Fields(3, "x", 1, PointField::FLOAT64, "y", 1, PointField::FLOAT64, "z", 1,
                             PointField::FLOAT64);
  }
  mod.resize(pts.size());
  sensor_msgs::PointCloud2Iterator<Scalar> x(c, "x"), y(c, "y"), z(c, "z");
  for (const auto& p : pts) {
    *x = p.x();
    *y = p.y();
    *z = p.z();
    ++x, ++y, ++z;
  }
  return c;
}

/// The scene, in the camera frame: a table top (0.6 x 0.6 m at 0.58 m, x from 0.0 to 0.6) and
/// a standing cylinder (r 3 cm, 12 cm tall) under the camera.
PointList sceneInCamera() {
  Surface scene = tableSurface(0.3, 0.0, 0.6, 0.6, kTableZ, 0.006);
  Surface cyl = cylinderSurface(0.03, 0.0, 0.12, 0.003, false, true);
  cyl.transform(pose(0.3, 0.0, kTableZ, 0.0));
  scene.append(cyl);
  const Eigen::Isometry3f camFromWorld = worldFromCamera().inverse().cast<float>();
  PointList pts = scene.noisy(0.001, 3);
  for (auto& p : pts) p = camFromWorld * p;
  return pts;
}

/// `good` with its layout broken in each way a fault campaign found or the validation rejects;
/// the data bytes stay `good`'s unless the fault is about them.
std::vector<sensor_msgs::PointCloud2> malformedClouds(const sensor_msgs::PointCloud2& good) {
  std::vector<sensor_msgs::PointCloud2> bad;
  auto add = [&](const char* /*fault*/, const std::function<void(sensor_msgs::PointCloud2&)>& f) {
    bad.push_back(good);
    f(bad.back());
  };
  add("point_step 0, large width, no data", [](auto& c) {
    c.width = 1000000;
    c.height = 1;
    c.point_step = c.row_step = 0;
    c.data.clear();
  });
  add("z offset beyond point_step", [](auto& c) { c.fields[2].offset = c.point_step; });
  add("data shorter than claimed", [](auto& c) { c.data.resize(c.data.size() / 2); });
  add("row_step smaller than a row", [](auto& c) { c.row_step = c.point_step; });
  add("width x height beyond 2^32", [](auto& c) {
    c.width = 65536;
    c.height = 65537;
    c.row_step = c.width * c.point_step;
  });
  add("no z field", [](auto& c) { c.fields.pop_back(); });
  add("UINT8 x, y, z", [](auto& c) {
    for (auto& f : c.fields) f.datatype = sensor_msgs::PointField::UINT8;
  });
  add("INT16 x, y, z", [](auto& c) {
    for (auto& f : c.fields) f.datatype = sensor_msgs::PointField::INT16;
  });
  add("big-endian", [](auto& c) { c.is_bigendian = true; });
  return bad;
}

class PerceptionNodes : public ::testing::Test {
 protected:
  void SetUp() override {
    cam_ = ehc_control::loadPinholeCamera(cameraYaml());
    image_pub_ = nh_.advertise<sensor_msgs::Image>("/camera/color/image_raw", 1);
    info_pub_ = nh_.advertise<sensor_msgs::CameraInfo>("/camera/color/camera_info", 1);
    cloud_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("/camera/depth/points", 1);
    joints_pub_ = nh_.advertise<sensor_msgs::JointState>("/joint_states", 5);
    odom_pub_ = nh_.advertise<nav_msgs::Odometry>("/odom", 5);
    target_sub_ = nh_.subscribe("/ehc/target_pose", 5, &PerceptionNodes::onTarget, this);
    grasp_sub_ = nh_.subscribe("/ehc/grasp_candidates", 5, &PerceptionNodes::onGrasps, this);
    obst_sub_ = nh_.subscribe("/ehc/obstacles", 50, &PerceptionNodes::onObstacles, this);

    static_tf_.sendTransform(cameraPoseAt(ros::Time::now()));

    // Image (rgb8) with tag 0 of 4 cm (its size in config/perception/tag_node.yaml).
    const vpImage<unsigned char> gray = TagImageRenderer(cam_).render({{0, 0.04, kTagInCamera}});
    image_.header.frame_id = kCamFrame;
    image_.width = gray.getWidth();
    image_.height = gray.getHeight();
    image_.encoding = "rgb8";
    image_.step = 3 * image_.width;
    image_.data.resize(image_.step * image_.height);
    for (unsigned r = 0; r < image_.height; ++r)
      for (unsigned c = 0; c < image_.width; ++c)
        for (int k = 0; k < 3; ++k) image_.data[r * image_.step + 3 * c + k] = gray[r][c];
    info_.header.frame_id = kCamFrame;
    info_.width = 640;
    info_.height = 480;
    info_.distortion_model = "plumb_bob";
    info_.D.assign(5, 0.0);
    info_.K = {cam_.fx, 0, cam_.cx, 0, cam_.fy, cam_.cy, 0, 0, 1};

    scene_in_camera_ = sceneInCamera();
    cloud_ = xyzCloud<float>(scene_in_camera_);
  }

  /// `state_stamp_offset` (s) is added to the stamps of /joint_states and /odom (a sender's
  /// clock offset); `state` false publishes no state at all.
  void publishAll(bool state_valid, double state_stamp_offset = 0.0, bool state = true) {
    const ros::Time now = ros::Time::now();
    image_.header.stamp = info_.header.stamp = cloud_.header.stamp = now;
    info_pub_.publish(info_);
    image_pub_.publish(image_);
    cloud_pub_.publish(cloud_);
    if (!state) return;
    const ros::Time state_stamp = now + ros::Duration(state_stamp_offset);
    sensor_msgs::JointState js;
    js.header.stamp = state_stamp;
    js.name = {"joint1", "joint2", "joint3", "joint4", "joint5", "joint6"};
    js.position = {0.0, 0.5, -1.9, 0.0, -0.5, 0.0};
    if (!state_valid) js.position[2] = std::nan("");
    joints_pub_.publish(js);
    nav_msgs::Odometry od;
    od.header.stamp = state_stamp;
    od.header.frame_id = "odom";
    od.pose.pose.position.x = -0.5;
    od.pose.pose.orientation.w = 1.0;
    odom_pub_.publish(od);
  }

  /// Publishes at 20 Hz until `done()` or the deadline (seconds); true if done.
  bool spinUntil(const std::function<bool()>& done, double seconds, bool state_valid = true,
                 double state_stamp_offset = 0.0, bool state = true) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
    ros::WallRate rate(20.0);
    while (ros::ok() && ros::WallTime::now() < end) {
      publishAll(state_valid, state_stamp_offset, state);
      ros::spinOnce();
      if (done()) return true;
      rate.sleep();
    }
    return done();
  }

  void onTarget(const geometry_msgs::PoseStamped& m) { targets_.push_back(m); }
  void onGrasps(const ehc_msgs::GraspCandidates& m) { grasps_.push_back(m); }
  void onObstacles(const ehc_msgs::ObstacleArray& m) { obstacles_.push_back(m); }

  ros::NodeHandle nh_;
  ehc_control::PinholeCamera cam_;
  tf2_ros::StaticTransformBroadcaster static_tf_;
  ros::Publisher image_pub_, info_pub_, cloud_pub_, joints_pub_, odom_pub_;
  ros::Subscriber target_sub_, grasp_sub_, obst_sub_;
  sensor_msgs::Image image_;
  sensor_msgs::CameraInfo info_;
  PointList scene_in_camera_;
  sensor_msgs::PointCloud2 cloud_;  ///< published by publishAll
  std::vector<geometry_msgs::PoseStamped> targets_;
  std::vector<ehc_msgs::GraspCandidates> grasps_;
  std::vector<ehc_msgs::ObstacleArray> obstacles_;
};

}  // namespace

TEST_F(PerceptionNodes, TagNodePublishesTheTargetInOdom) {
  ASSERT_TRUE(spinUntil([&] { return !targets_.empty(); }, 30.0)) << "no /ehc/target_pose";
  const auto& m = targets_.back();
  EXPECT_EQ(m.header.frame_id, "odom");
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  tf2::fromMsg(m.pose, T);
  // Expected: the tag pose composed with the grasp offset of the shipped config.
  const auto root = ehc_common::ConfigNode::loadFile(
      configDir() + "/perception/tag_node.yaml", "TagNode");
  const TagTargetConfig target = loadTagTargetConfig(root.child("target"));
  EXPECT_EQ(target.tag_id, 0);
  const Eigen::Isometry3d truth = worldFromCamera() * kTagInCamera * target.offset();
  EXPECT_LT((T.translation() - truth.translation()).norm(), 0.005)
      << T.translation().transpose() << " vs " << truth.translation().transpose();
  EXPECT_LT(Eigen::AngleAxisd(T.linear().transpose() * truth.linear()).angle(), 2.0 * M_PI / 180);
}

TEST_F(PerceptionNodes, TagNodeWaitsForTheCameraPoseOfALateImage) {
  // Under load the camera pose (tf) at an image's stamp can reach the tag node after
  // the image: the image used to be dropped after a lookup timeout on ROS time (0.05 s). It now
  // waits on the wall clock up to tf_timeout (config/perception/tag_node.yaml: 1 s). Here an
  // image in a frame with no pose yet; its pose follows 0.5 s later; the target must come, at
  // that stamp.
  ASSERT_TRUE(spinUntil([&] { return !targets_.empty(); }, 30.0)) << "the tag node does not run";
  const char* late_frame = "late_camera";
  sensor_msgs::Image image = image_;
  const ros::Time stamp = ros::Time::now();
  image.header.stamp = stamp;
  image.header.frame_id = late_frame;
  image_pub_.publish(image);
  const ros::WallTime t0 = ros::WallTime::now();
  while (ros::WallTime::now() - t0 < ros::WallDuration(0.5)) {
    ros::spinOnce();
    ros::WallDuration(0.01).sleep();
  }
  for (const auto& m : targets_) EXPECT_NE(m.header.stamp, stamp) << "a target without a camera pose";
  geometry_msgs::TransformStamped tf = cameraPoseAt(stamp);
  tf.child_frame_id = late_frame;
  tf2_ros::TransformBroadcaster broadcaster;
  const ros::WallTime t1 = ros::WallTime::now();
  bool got = false;
  while (!got && ros::WallTime::now() - t1 < ros::WallDuration(10.0)) {
    broadcaster.sendTransform(tf);  // until the node's listener is connected
    ros::spinOnce();
    for (const auto& m : targets_) got = got || m.header.stamp == stamp;
    ros::WallDuration(0.05).sleep();
  }
  ASSERT_TRUE(got) << "the late image was dropped instead of waiting for its camera pose";
}

TEST_F(PerceptionNodes, GraspNodePublishesGraspsOnTheObjectNearTheTarget) {
  auto nonEmpty = [&] {
    for (const auto& g : grasps_)
      if (!g.poses.empty()) return true;
    return false;
  };
  ASSERT_TRUE(spinUntil(nonEmpty, 40.0)) << "no non-empty /ehc/grasp_candidates";
  const ehc_msgs::GraspCandidates* g = nullptr;
  for (const auto& c : grasps_)
    if (!c.poses.empty()) g = &c;
  EXPECT_EQ(g->header.frame_id, "odom");
  ASSERT_EQ(g->poses.size(), g->widths.size());
  ASSERT_EQ(g->poses.size(), g->scores.size());
  for (std::size_t i = 0; i < g->poses.size(); ++i) {
    const auto& p = g->poses[i].position;
    EXPECT_LT(std::hypot(p.x - 0.3, p.y - 0.0), 0.05);
    EXPECT_GT(p.z, kTableZ);
    EXPECT_LT(g->widths[i], 0.07);
    if (i > 0) {
      EXPECT_GE(g->scores[i - 1], g->scores[i]);
    }
  }
}

TEST_F(PerceptionNodes, ObstacleNodePublishesDistancesAndStopsOnABadState) {
  auto baseSeen = [&] {
    for (const auto& a : obstacles_)
      for (const auto& o : a.obstacles)
        if (o.link == "base_link") return true;
    return false;
  };
  ASSERT_TRUE(spinUntil(baseSeen, 40.0)) << "no base_link distance on /ehc/obstacles";
  const ehc_msgs::ObstacleArray* a = nullptr;
  for (const auto& m : obstacles_)
    for (const auto& o : m.obstacles)
      if (o.link == "base_link") a = &m;
  EXPECT_EQ(a->header.frame_id, "odom");
  EXPECT_DOUBLE_EQ(a->influence_distance, 0.30);
  for (const auto& o : a->obstacles) {
    const Eigen::Vector3d n(o.normal.x, o.normal.y, o.normal.z);
    EXPECT_NEAR(n.norm(), 1.0, 1e-6);
    EXPECT_LE(o.distance, 0.30);
    if (o.link == "base_link") {
      // Base cylinder (r 0.25, top 0.60) at x = -0.5; table front edge at x = 0.0, top 0.58.
      EXPECT_NEAR(o.distance, 0.25, 0.021);
      EXPECT_NEAR(o.normal.x, -1.0, 0.1);
    }
  }
  // A NaN joint state is rejected: once the last good state is older than the timeout,
  // nothing more is published.
  spinUntil([] { return false; }, 1.0, /*state_valid=*/false);
  obstacles_.clear();
  spinUntil([] { return false; }, 1.0, /*state_valid=*/false);
  EXPECT_TRUE(obstacles_.empty()) << obstacles_.size() << " messages with a NaN state";
}

// The obstacle node judges the state's freshness by receipt time on its own clock
// (like the controller's watchdogs), not by header stamps. A state stamped 10 s in the past (a
// sender's clock offset) but arriving now is fresh: distances are published (by stamps: stale,
// nothing). A state stamped 10 s in the future that stops arriving goes stale after the
// timeout (by stamps it would count as fresh for 10 s more).
TEST_F(PerceptionNodes, ObstacleNodeJudgesStateFreshnessByReceiptTime) {
  auto anyPublished = [&] { return !obstacles_.empty(); };
  obstacles_.clear();
  ASSERT_TRUE(spinUntil(anyPublished, 40.0, true, /*state_stamp_offset=*/-10.0))
      << "a live state stamped 10 s in the past was judged stale: no /ehc/obstacles";

  obstacles_.clear();
  ASSERT_TRUE(spinUntil(anyPublished, 10.0, true, +10.0)) << "a live state stamped in the future: no /ehc/obstacles";
  // The state stops (clouds go on): after the state timeout (0.2 s) nothing more is published.
  spinUntil([] { return false; }, 1.0, true, 0.0, /*state=*/false);
  obstacles_.clear();
  spinUntil([] { return false; }, 1.0, true, 0.0, /*state=*/false);
  EXPECT_TRUE(obstacles_.empty()) << obstacles_.size()
                                  << " /ehc/obstacles messages 1-2 s after the last (future-stamped) state";
}

// Malformed clouds: both cloud nodes reject each with a logged reason before
// reading it, stay alive, publish nothing made from it, and afterwards process a valid FLOAT64
// cloud of the scene (grasps on the cylinder; the base's distance to the table).
TEST_F(PerceptionNodes, MalformedCloudsAreRejectedAndTheNodesKeepWorking) {
  // The bad clouds carry the scene and a ghost box 0.10 m behind the robot base: a bad cloud
  // read as points would put an obstacle there, nearer the base than the table.
  Surface ghost = boxSurface(Eigen::Vector3d(0.15, 0.2, 0.4), 0.01);
  ghost.transform(pose(-0.925, 0.0, 0.3, 0.0));
  PointList with_ghost = scene_in_camera_;
  const Eigen::Isometry3f camFromWorld = worldFromCamera().inverse().cast<float>();
  for (const auto& p : ghost.points) with_ghost.push_back(camFromWorld * p);
  // On the table top (x 0 .. 0.6, |y| <= 0.3, z 0.58) or the cylinder on it: the real scene.
  auto inScene = [](const geometry_msgs::Point& p) {
    return p.x > -0.05 && p.x < 0.65 && std::abs(p.y) < 0.35 && p.z > 0.5 && p.z < 0.75;
  };

  std::vector<rosgraph_msgs::Log> errors;
  const boost::function<void(const rosgraph_msgs::LogConstPtr&)> onLog =
      [&](const rosgraph_msgs::LogConstPtr& m) {
        if (m->level >= rosgraph_msgs::Log::ERROR) errors.push_back(*m);
      };
  ros::Subscriber log_sub = nh_.subscribe<rosgraph_msgs::Log>("/rosout", 200, onLog);

  const ros::Time bad_start = ros::Time::now();
  for (const sensor_msgs::PointCloud2& bad : malformedClouds(xyzCloud<float>(with_ghost))) {
    cloud_ = bad;
    // Longer than one period of each node's cloud rate limit (grasp 2 Hz, obstacles 5 Hz).
    spinUntil([] { return false; }, 0.8);
  }
  const ros::Time good_start = ros::Time::now();
  EXPECT_TRUE(ros::service::exists("/ehc_grasp_node/get_loggers", false)) << "grasp node died";
  EXPECT_TRUE(ros::service::exists("/ehc_obstacle_node/get_loggers", false))
      << "obstacle node died";

  cloud_ = xyzCloud<double>(scene_in_camera_);
  auto freshGrasps = [&] {
    for (const auto& g : grasps_)
      if (g.header.stamp >= good_start && !g.poses.empty()) return &g;
    return static_cast<const ehc_msgs::GraspCandidates*>(nullptr);
  };
  auto freshBaseDistance = [&] {
    for (const auto& a : obstacles_)
      for (const auto& o : a.obstacles)
        if (a.header.stamp >= good_start && o.link == "base_link") return &o;
    return static_cast<const ehc_msgs::ObstacleDistance*>(nullptr);
  };
  ASSERT_TRUE(spinUntil([&] { return freshGrasps() && freshBaseDistance(); }, 40.0))
      << "no grasps or no base_link distance after the malformed clouds";
  for (const auto& p : freshGrasps()->poses)
    EXPECT_LT(std::hypot(p.position.x - 0.3, p.position.y - 0.0), 0.05);
  EXPECT_NEAR(freshBaseDistance()->distance, 0.25, 0.021);

  int from_bad_clouds = 0;
  for (const auto& g : grasps_)
    from_bad_clouds += g.header.stamp >= bad_start && g.header.stamp < good_start;
  EXPECT_EQ(from_bad_clouds, 0) << "grasp messages from malformed clouds";
  std::string not_in_scene;
  for (const auto& a : obstacles_)
    for (const auto& o : a.obstacles)
      if (!inScene(o.obstacle_point) && not_in_scene.empty())
        not_in_scene = o.link + " at " + std::to_string(o.obstacle_point.x) + " " +
                       std::to_string(o.obstacle_point.y) + " " + std::to_string(o.obstacle_point.z);
  EXPECT_EQ(not_in_scene, "") << "an obstacle that is not in the scene";
  auto rejected = [&](const std::string& node) {
    for (const auto& e : errors)
      if (e.name == node && e.msg.find("cloud dropped: [PointCloudLayout]") != std::string::npos)
        return true;
    return false;
  };
  EXPECT_TRUE(rejected("/ehc_grasp_node")) << "no malformed-cloud error logged";
  EXPECT_TRUE(rejected("/ehc_obstacle_node")) << "no malformed-cloud error logged";
}

// The grasp node in lock-step (grasp_node_lockstep.test: sim time, _ack_topic): this test is
// the simulator (it owns /clock and publishes, like ehc_sim_node, each cloud before the camera
// pose of its stamp) and checks that every cloud is acknowledged exactly once, whatever came of
// it: processed (candidates published before the acknowledgement), skipped by the 2 Hz rate
// limit, or dropped with a logged reason when its camera pose never arrives (once the wall-clock
// wait is over; sim time stands still meanwhile). The wall-clock deadlines only guard against a
// hang: a tf2_ros::MessageFilter held the cloud without a pose for good, so the simulator stalled.
class GraspNodeLockstep : public ::testing::Test {
 protected:
  void SetUp() override {
    clock_pub_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 1, true);
    cloud_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("/camera/depth/points", 5);
    target_pub_ = nh_.advertise<geometry_msgs::PoseStamped>("/ehc/target_pose", 5);
    ack_sub_ = nh_.subscribe("/sim/lockstep_ack", 50, &GraspNodeLockstep::onAck, this);
    grasp_sub_ = nh_.subscribe("/ehc/grasp_candidates", 50, &GraspNodeLockstep::onGrasps, this);
    log_sub_ = nh_.subscribe("/rosout", 200, &GraspNodeLockstep::onLog, this);
    cloud_ = xyzCloud<float>(sceneInCamera());
    setClock(ros::Time(1.0));
  }

  void setClock(const ros::Time& t) {
    rosgraph_msgs::Clock c;
    c.clock = t;
    clock_pub_.publish(c);
  }

  /// One simulator step at `t`: the cloud, then (if `with_pose`) the camera pose at t on /tf;
  /// then waits (wall-clock guard) for the node's acknowledgement of t.
  bool step(const ros::Time& t, bool with_pose) {
    setClock(t);
    cloud_.header.stamp = t;
    cloud_pub_.publish(cloud_);
    if (with_pose) tf_.sendTransform(cameraPoseAt(t));
    return spinUntil([&] { return acks_.count(t) > 0; }, 30.0);
  }

  static bool spinUntil(const std::function<bool()>& done, double wall_s) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(wall_s);
    while (ros::ok() && !done() && ros::WallTime::now() < end) {
      ros::spinOnce();
      ros::WallDuration(0.005).sleep();
    }
    return done();
  }

  void onAck(const std_msgs::Header& m) {
    if (m.frame_id == "/ehc_grasp_node") ++acks_[m.stamp];
  }
  void onGrasps(const ehc_msgs::GraspCandidates& m) { grasp_stamps_.push_back(m.header.stamp); }
  void onLog(const rosgraph_msgs::Log& m) {
    if (m.name == "/ehc_grasp_node" && m.level >= rosgraph_msgs::Log::WARN) warnings_.push_back(m.msg);
  }

  ros::NodeHandle nh_;
  ros::Publisher clock_pub_, cloud_pub_, target_pub_;
  ros::Subscriber ack_sub_, grasp_sub_, log_sub_;
  tf2_ros::TransformBroadcaster tf_;
  sensor_msgs::PointCloud2 cloud_;
  std::map<ros::Time, int> acks_;  ///< acknowledgements per stamp (0: "ready")
  std::vector<ros::Time> grasp_stamps_;
  std::vector<std::string> warnings_;
};

TEST_F(GraspNodeLockstep, EveryCloudIsAcknowledgedOnceWhateverCameOfIt) {
  ASSERT_TRUE(spinUntil([&] { return acks_.count(ros::Time(0)) > 0; }, 60.0))
      << "the grasp node never announced it is ready for the lock-step";
  const ros::Time processed(1.0), rate_limited(1.2), without_pose(2.0), processed_after(3.0);
  ASSERT_TRUE(step(processed, true)) << "a cloud with its camera pose was not acknowledged";
  ASSERT_TRUE(step(rate_limited, true)) << "a cloud inside the rate limit was not acknowledged";
  ASSERT_TRUE(step(without_pose, false)) << "a cloud whose camera pose never comes was not acknowledged";
  ASSERT_TRUE(step(processed_after, true)) << "the node does not process clouds after a dropped one";
  // Candidates are published before the acknowledgement, but on another connection.
  auto hasGrasps = [&](const ros::Time& t) {
    return std::count(grasp_stamps_.begin(), grasp_stamps_.end(), t) == 1;
  };
  ASSERT_TRUE(spinUntil([&] { return hasGrasps(processed) && hasGrasps(processed_after); }, 30.0))
      << "no candidates for the processed clouds";
  // In order on one connection: nothing else was published before the last cloud's candidates.
  EXPECT_EQ(grasp_stamps_, (std::vector<ros::Time>{processed, processed_after}));
  for (const ros::Time& t : {processed, rate_limited, without_pose, processed_after})
    EXPECT_EQ(acks_[t], 1) << "cloud at " << t << " acknowledged " << acks_[t] << " times";
  ASSERT_TRUE(spinUntil(
      [&] {
        return std::any_of(warnings_.begin(), warnings_.end(),
                           [](const std::string& w) { return w.find("dropped: no camera pose") != std::string::npos; });
      },
      30.0))
      << "no reason logged for the cloud without a camera pose";
  for (const std::string& w : warnings_)  // the targets were taken first (ehc_common::PollPassBarrier)
    EXPECT_EQ(w.find("poll thread"), std::string::npos) << w;
}

// A target without a tag (grasp_node_cloud_target.test): the node, given a `nearest` selector
// on its selector_topic, finds the cylinder in the scene cloud and publishes its pose and the
// box of its cluster, which the grasp sequencer's obstacle exclusion follows.
class GraspNodeCloudTarget : public ::testing::Test {
 protected:
  void SetUp() override {
    cloud_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("/camera/depth/points", 1);
    selector_pub_ = nh_.advertise<ehc_msgs::TargetSelector>("/ehc/sequencer/target_selector", 1, true);  // latched
    target_sub_ = nh_.subscribe("/ehc/perception/cloud_target", 5, &GraspNodeCloudTarget::onTarget, this);
    static_tf_.sendTransform(cameraPoseAt(ros::Time::now()));
    cloud_ = xyzCloud<float>(sceneInCamera());
  }
  void select(const Eigen::Vector3d& point) {
    ehc_msgs::TargetSelector m;
    m.header.frame_id = "odom";
    m.header.stamp = ros::Time::now();
    m.select = "nearest";
    m.point.x = point.x(), m.point.y = point.y(), m.point.z = point.z();
    m.k = 1;
    selector_pub_.publish(m);
  }
  /// Publishes the cloud at 20 Hz until `done()` or the wall-clock deadline.
  bool spinUntil(const std::function<bool()>& done, double seconds) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
    ros::WallRate rate(20.0);
    while (ros::ok() && ros::WallTime::now() < end && !done()) {
      cloud_.header.stamp = ros::Time::now();
      cloud_pub_.publish(cloud_);
      ros::spinOnce();
      rate.sleep();
    }
    return done();
  }
  void onTarget(const ehc_msgs::CloudTarget& m) { targets_.push_back(m); }

  ros::NodeHandle nh_;
  tf2_ros::StaticTransformBroadcaster static_tf_;
  ros::Publisher cloud_pub_, selector_pub_;
  ros::Subscriber target_sub_;
  sensor_msgs::PointCloud2 cloud_;
  std::vector<ehc_msgs::CloudTarget> targets_;
};

TEST_F(GraspNodeCloudTarget, TheTargetComesWithItsClustersBox) {
  select(Eigen::Vector3d(0.32, 0.02, kTableZ + 0.05));  // near the cylinder (r 3 cm, 12 cm tall, at (0.3, 0))
  ASSERT_TRUE(spinUntil([&] { return !targets_.empty(); }, 40.0)) << "no cloud target published";
  const ehc_msgs::CloudTarget& m = targets_.back();
  EXPECT_EQ(m.header.frame_id, "odom");
  EXPECT_LT(std::hypot(m.pose.position.x - 0.3, m.pose.position.y), 0.02);
  // The box: upright, down to the table, about the cylinder's size (the view from straight above
  // shows its top and little of its side; the box is as deep as it is wide).
  EXPECT_LT(std::hypot(m.extent_pose.position.x - 0.3, m.extent_pose.position.y), 0.02);
  EXPECT_NEAR(m.extent_pose.position.z, kTableZ + 0.06, 0.01);
  EXPECT_NEAR(m.half_extents.z, 0.06, 0.01);
  EXPECT_NEAR(m.half_extents.x, 0.03, 0.01);
  EXPECT_NEAR(m.half_extents.y, 0.03, 0.01);
  const Eigen::Quaterniond q(m.extent_pose.orientation.w, m.extent_pose.orientation.x, m.extent_pose.orientation.y,
                             m.extent_pose.orientation.z);
  EXPECT_NEAR(std::abs((q.toRotationMatrix().col(2)).z()), 1.0, 1e-6) << "the box's third axis is up";
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_perception_nodes");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
