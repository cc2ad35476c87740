// rostest of ehc_sim_node in lock-step: this node plays the controller (one command per state,
// /cmd_vel then /arm/joint_velocity_cmd stamped with the state's stamp). Checks: a commanded
// twist moves the base by the expected distance; same seed => identical trajectories; bad
// commands rejected and counted without stalling; grasp at the object centre succeeds after
// a 10 cm lift and 10 cm off fails; camera image (AprilTag detected, pose vs ground truth via
// /tf and /sim/object_poses) and depth cloud (table top at the table height).
// No assertion depends on wall time; wall timeouts only stop a hung test.

#include "lock_step_controller.h"

#include "ehc_control/gripper_state.h"
#include "ehc_control/whole_body_model.h"
#include "ehc_msgs/ResetScene.h"
#include "ehc_msgs/SimObjectPoses.h"
#include "ehc_msgs/SimStatus.h"

#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/JointState.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <std_srvs/SetBool.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "ehc_perception/tag_detector.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <functional>
#include <memory>

namespace {

using ehc_control::GripperState;

Eigen::Isometry3d toEigen(const geometry_msgs::Pose& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z)
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  return T;
}

using ehc_sim::test::State;

/// The shared lock-step controller plus what only the Bullet simulator has: ground-truth
/// object poses, the camera, tf of every link, the reset and gripper services.
class FakeController : public ehc_sim::test::LockStepController {
 public:
  FakeController() {
    ros::NodeHandle nh;
    const auto fast = ros::TransportHints().tcpNoDelay();
    objects_sub_ = nh.subscribe("/sim/object_poses", 100, &FakeController::onObjects, this, fast);
    image_sub_ = nh.subscribe("/camera/color/image_raw", 5, &FakeController::onImage, this);
    info_sub_ = nh.subscribe("/camera/color/camera_info", 5, &FakeController::onInfo, this);
    cloud_sub_ = nh.subscribe("/camera/depth/points", 5, &FakeController::onCloud, this);
    reset_ = nh.serviceClient<ehc_msgs::ResetScene>("/sim/reset");
    gripper_ = nh.serviceClient<std_srvs::SetBool>("/sim/gripper");
    tf_ = std::make_unique<tf2_ros::TransformListener>(buffer_);
  }

  bool connected() override {
    return LockStepController::connected() && spinUntil([&] { return reset_.exists() && gripper_.exists(); });
  }

  /// Resets the sim and waits for its first state (stamp 1 s).
  bool reset(unsigned seed, const std::string& scene = "") {
    ehc_msgs::ResetScene srv;
    srv.request.seed = seed;
    srv.request.scene_file = scene;
    if (!reset_.call(srv) || !srv.response.success) return false;
    last_answered_ = ros::Time();
    return waitState(ros::Time(1.0));
  }

  bool gripper(bool close) {
    std_srvs::SetBool srv;
    srv.request.data = close;
    return gripper_.call(srv) && srv.response.success;
  }

  ehc_msgs::SimObjectPoses objects_;
  sensor_msgs::Image::ConstPtr image_;
  sensor_msgs::CameraInfo::ConstPtr info_;
  sensor_msgs::PointCloud2::ConstPtr cloud_;
  tf2_ros::Buffer buffer_{ros::Duration(30.0)};

 private:
  void onObjects(const ehc_msgs::SimObjectPoses::ConstPtr& m) { objects_ = *m; }
  void onImage(const sensor_msgs::Image::ConstPtr& m) { image_ = m; }
  void onInfo(const sensor_msgs::CameraInfo::ConstPtr& m) { info_ = m; }
  void onCloud(const sensor_msgs::PointCloud2::ConstPtr& m) { cloud_ = m; }

  ros::Subscriber objects_sub_, image_sub_, info_sub_, cloud_sub_;
  ros::ServiceClient reset_, gripper_;
  std::unique_ptr<tf2_ros::TransformListener> tf_;
};

FakeController* ctl = nullptr;
std::string scenes, test_scenes, robot_file;

void zeroPolicy(int, const State&, geometry_msgs::Twist*, std::vector<double>*) {}

}  // namespace

TEST(SimNode, TwistMovesTheBaseByTheExpectedDistance) {
  ASSERT_TRUE(ctl->reset(1));
  const auto states = ctl->run(100, [](int, const State&, geometry_msgs::Twist* b, std::vector<double>*) {
    b->linear.x = 0.2;
  });
  ASSERT_EQ(states.size(), 101u);
  // One state per answered command, 10 ms apart, exactly.
  for (std::size_t k = 0; k < states.size(); ++k)
    EXPECT_EQ(states[k].stamp, ros::Time(1.0) + ros::Duration(0.01 * static_cast<double>(k))) << k;
  EXPECT_EQ(ctl->clock_, states.back().stamp);
  // 0.2 m/s for 1 s; Table I noise (sigma 0.05 m/s per step) => sigma(x) = 5 mm.
  EXPECT_NEAR(states.back().x, 0.2, 0.02);
  EXPECT_NEAR(states.back().y, 0.0, 0.01);
  EXPECT_EQ(ctl->status_.step, 100u);
  EXPECT_FALSE(ctl->status_.robot_world_collision);
}

TEST(SimNode, SameSeedGivesIdenticalTrajectories) {
  auto policy = [](int k, const State&, geometry_msgs::Twist* b, std::vector<double>* arm) {
    b->linear.x = 0.3 * std::sin(0.05 * k);
    b->angular.z = 0.2;
    (*arm)[0] = 0.2;
    (*arm)[4] = -0.1 * std::cos(0.03 * k);
  };
  ASSERT_TRUE(ctl->reset(7));
  const auto a = ctl->run(150, policy);
  ASSERT_TRUE(ctl->reset(7));
  const auto b = ctl->run(150, policy);
  ASSERT_TRUE(ctl->reset(8));
  const auto c = ctl->run(150, policy);
  ASSERT_EQ(a.size(), 151u);
  ASSERT_EQ(b.size(), a.size());
  ASSERT_EQ(c.size(), a.size());
  double diff_c = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].stamp, b[k].stamp);
    EXPECT_EQ(a[k].x, b[k].x) << k;  // bit-identical
    EXPECT_EQ(a[k].y, b[k].y) << k;
    EXPECT_EQ(a[k].yaw, b[k].yaw) << k;
    EXPECT_EQ(a[k].q, b[k].q) << k;
    diff_c = std::max(diff_c, std::abs(a[k].x - c[k].x) + std::abs(a[k].yaw - c[k].yaw));
  }
  EXPECT_GT(diff_c, 1e-3) << "another seed must give another noise sequence";
}

TEST(SimNode, BadCommandsAreRejectedCountedAndDoNotStall) {
  ASSERT_TRUE(ctl->reset(2));
  const auto states = ctl->run(6, [](int k, const State&, geometry_msgs::Twist* b, std::vector<double>* arm) {
    b->linear.x = 0.1;
    (*arm)[1] = 0.5;
    if (k == 2) (*arm)[1] = std::nan("");   // NaN arm command
    if (k == 3) b->linear.x = 5.0;          // over the 0.5 m/s limit
    if (k == 4) (*arm)[2] = 100.0;          // over the joint3 limit
  });
  ASSERT_EQ(states.size(), 7u) << "lock-step went on";
  EXPECT_EQ(ctl->status_.arm_commands_rejected, 2u);
  EXPECT_EQ(ctl->status_.base_commands_rejected, 1u);
  // The step after a rejected arm command executed zero arm rates (plus the Table I actuation
  // noise, sigma 0.002 rad/s, since the base still moves).
  for (double v : states[3].qd) EXPECT_NEAR(v, 0.0, 0.01);
  for (double v : states[5].qd) EXPECT_NEAR(v, 0.0, 0.01);
  EXPECT_NEAR(states[4].x - states[3].x, 0.0, 0.003) << "rejected /cmd_vel: base stopped (noise only)";
  EXPECT_NEAR(states[2].qd[1], 0.5, 0.02);
}

TEST(SimNode, GraspAtTheCentreSucceedsAndTenCentimetresOffFails) {
  const ehc_control::WholeBodyModel model(ehc_control::loadRobotConfig(robot_file));
  auto lift = [&](int, const State& s, geometry_msgs::Twist*, std::vector<double>* arm) {
    const Eigen::Vector3d base(s.x, s.y, s.yaw);
    const Eigen::VectorXd q = Eigen::Map<const Eigen::VectorXd>(s.q.data(), 6);
    const Eigen::MatrixXd J = model.jacobian(base, q, "ee_link").rightCols(6);
    Eigen::VectorXd twist = Eigen::VectorXd::Zero(6);
    twist[2] = 0.1;  // 10 cm/s up, orientation held
    const Eigen::VectorXd qd = J.completeOrthogonalDecomposition().solve(twist);
    for (int i = 0; i < 6; ++i) (*arm)[static_cast<std::size_t>(i)] = qd[i];
  };
  for (const char* scene : {"grasp_center.yaml", "grasp_off.yaml"}) {
    SCOPED_TRACE(scene);
    const bool centre = std::string(scene) == "grasp_center.yaml";
    ASSERT_TRUE(ctl->reset(3, test_scenes + "/" + scene));
    ctl->run(5, zeroPolicy);
    const double z0 = ctl->objects_.poses.at(0).position.z;
    ASSERT_TRUE(ctl->gripper(true));
    ctl->run(1, zeroPolicy);
    // /sim/status carries the one string map of ehc_control::GripperState.
    auto gripperState = [&] { return ehc_control::gripperStateFromString(ctl->status_.gripper_state); };
    EXPECT_EQ(gripperState(), GripperState::Closing);
    for (int i = 0; i < 150 && gripperState() == GripperState::Closing; ++i) ctl->run(1, zeroPolicy);
    EXPECT_EQ(gripperState(), centre ? GripperState::Holding : GripperState::ClosedEmpty);
    ctl->run(120, lift);  // 12 cm
    ctl->run(1, zeroPolicy);
    const double z1 = ctl->objects_.poses.at(0).position.z;
    EXPECT_EQ(ctl->status_.grasp_succeeded, centre);
    EXPECT_EQ(ctl->status_.grasp_successes, centre ? 1u : 0u);
    EXPECT_EQ(ctl->status_.grasp_failures, centre ? 0u : 1u);
    EXPECT_EQ(ctl->objects_.held.at(0), centre);
    if (centre) {
      EXPECT_GT(z1 - z0, 0.10);
      EXPECT_EQ(ctl->status_.held_object, "box");
    } else {
      EXPECT_NEAR(z1, z0, 0.002) << "the object stays on its pedestal";
    }
  }
}

TEST(SimNode, CameraSeesTheTagAndTheTableTop) {
  ASSERT_TRUE(ctl->reset(4, scenes + "/single_object.yaml"));
  ctl->image_.reset();
  ctl->cloud_.reset();
  ctl->run(10, zeroPolicy);  // images at 15 Hz of sim time: one within 67 ms
  ASSERT_TRUE(ctl->spinUntil([&] { return ctl->image_ && ctl->info_ && ctl->cloud_; }));
  const sensor_msgs::Image& img = *ctl->image_;
  EXPECT_EQ(img.encoding, "mono8");
  ASSERT_EQ(img.width, 640u);
  ASSERT_EQ(img.height, 480u);
  EXPECT_EQ(img.header.frame_id, "camera_color_optical_frame");
  EXPECT_EQ(ctl->info_->K[0], 615.0);
  // The project's tag detector on the published image vs ground truth from /tf +
  // /sim/object_poses (the camera pose at the image stamp is also the detector's prior).
  vpImage<unsigned char> I(img.height, img.width);
  std::copy(img.data.begin(), img.data.end(), I.bitmap);
  ASSERT_TRUE(ctl->spinUntil([&] {
    return ctl->buffer_.canTransform("odom", "camera_color_optical_frame", img.header.stamp);
  }));
  const Eigen::Isometry3d T_cam = tf2::transformToEigen(
      ctl->buffer_.lookupTransform("odom", "camera_color_optical_frame", img.header.stamp));
  ehc_perception::TagDetectorConfig tag_cfg;
  tag_cfg.default_tag_size = ctl->objects_.tag_sizes.at(0);
  ehc_control::PinholeCamera k;
  k.width = static_cast<int>(img.width);
  k.height = static_cast<int>(img.height);
  k.fx = ctl->info_->K[0];
  k.fy = ctl->info_->K[4];
  k.cx = ctl->info_->K[2];
  k.cy = ctl->info_->K[5];
  ehc_perception::TagDetector detector(tag_cfg, k);
  const std::vector<ehc_perception::TagDetection> dets = detector.detect(I, T_cam);
  ASSERT_EQ(dets.size(), 1u);
  EXPECT_EQ(dets[0].id, ctl->objects_.tag_ids.at(0));
  const Eigen::Isometry3d truth = T_cam.inverse() * toEigen(ctl->objects_.tag_poses.at(0));
  const Eigen::Isometry3d& det = dets[0].T_cam_tag;
  const Eigen::Isometry3d E = truth.inverse() * det;
  EXPECT_LT(E.translation().norm(), 0.03) << "tag ~1.1 m away, ~25 px wide";
  EXPECT_LT(Eigen::AngleAxisd(E.linear()).angle() * 180 / M_PI, 6.0);

  // Depth cloud of the table of table_three_objects.yaml: top at 0.75 m.
  ASSERT_TRUE(ctl->reset(4, scenes + "/table_three_objects.yaml"));
  ctl->cloud_.reset();
  ctl->run(10, zeroPolicy);
  ASSERT_TRUE(ctl->spinUntil([&] { return ctl->cloud_ != nullptr; }));
  const sensor_msgs::PointCloud2& cloud = *ctl->cloud_;
  EXPECT_EQ(cloud.header.frame_id, "camera_color_optical_frame");
  ASSERT_TRUE(ctl->spinUntil([&] {
    return ctl->buffer_.canTransform("odom", "camera_color_optical_frame", cloud.header.stamp);
  }));
  const Eigen::Isometry3d T = tf2::transformToEigen(
      ctl->buffer_.lookupTransform("odom", "camera_color_optical_frame", cloud.header.stamp));
  sensor_msgs::PointCloud2ConstIterator<float> x(cloud, "x"), y(cloud, "y"), z(cloud, "z");
  int n = 0;
  double sum = 0;
  for (; x != x.end(); ++x, ++y, ++z) {
    const Eigen::Vector3d p = T * Eigen::Vector3d(*x, *y, *z);
    bool near_object = false;
    for (const auto& o : ctl->objects_.poses)
      near_object |= std::hypot(p.x() - o.position.x, p.y() - o.position.y) < 0.08;
    if (near_object || p.x() < 1.6 || p.x() > 2.25 || std::abs(p.y()) > 0.5 || p.z() < 0.5) continue;
    EXPECT_NEAR(p.z(), 0.75, 0.03);  // > 5 sigma of the depth noise at ~1.5 m
    sum += p.z();
    ++n;
  }
  ASSERT_GT(n, 300);
  EXPECT_NEAR(sum / n, 0.75, 0.002);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_sim_node");
  ros::NodeHandle pnh("~");
  pnh.getParam("robot", robot_file);
  pnh.getParam("scenes", scenes);
  pnh.getParam("test_scenes", test_scenes);
  FakeController c;
  ctl = &c;
  if (!c.connected()) {
    ADD_FAILURE() << "ehc_sim_node did not come up";
    return 1;
  }
  return RUN_ALL_TESTS();
}
