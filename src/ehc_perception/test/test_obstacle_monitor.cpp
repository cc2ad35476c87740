// ObstacleMonitor (the logic of ehc_obstacle_node), without a ROS master: nothing is published
// while the joint state or odometry is missing, stale or rejected; the distances carry the
// newest state stamp; exclusion lists expire; cloud insertions are rate-limited; the robot's own
// points are removed only with a fresh state; the work per cloud is bounded (voxel decimation,
// point budget) for a full 640x480 D435 frame. ObstacleLockstepCycle: in lock-step a state is
// the joint state and odometry of one stamp, its distances due at publish_rate_hz of the stamps.
// Times are plain numbers: nothing is timed.

#include "ehc_common/config_node.h"
#include "ehc_perception/obstacle_monitor.h"
#include "ehc_test/perception_fixtures.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <limits>
#include <random>

using ehc_common::ConfigNode;

using namespace ehc_perception;

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Rig {
  ehc_control::RobotConfig robot = ehc_control::loadRobotConfig(test::robotYaml());
  ObstacleMonitor monitor{robot, ObstacleMapConfig(), ObstacleMonitorParams()};
  std::vector<double> ready() const {
    return std::vector<double>(robot.arm_ready.data(), robot.arm_ready.data() + robot.nArm());
  }
  /// Joint state and odometry (robot at the origin, arm ready) stamped `t`.
  void state(double t) {
    ASSERT_EQ(monitor.setJointState(t, robot.arm_joints, ready()), "");
    ASSERT_EQ(monitor.setBasePose(t, Eigen::Vector3d::Zero()), "");
  }
  /// A small block 15 cm in front of the base cylinder (radius 0.25 m).
  void addBlock() {
    monitor.field().addOccupiedBox(Eigen::Vector3d(0.40, -0.03, 0.20), Eigen::Vector3d(0.46, 0.03, 0.26));
  }
};

}  // namespace

TEST(ObstacleMonitor, NothingIsPublishedWithoutAFreshState) {
  Rig r;
  r.addBlock();
  EXPECT_EQ(r.monitor.update(10.0).status, ObstacleReport::Status::StateStale) << "no state yet";
  ASSERT_EQ(r.monitor.setJointState(10.0, r.robot.arm_joints, r.ready()), "");
  EXPECT_EQ(r.monitor.update(10.0).status, ObstacleReport::Status::StateStale) << "no odometry yet";
  ASSERT_EQ(r.monitor.setBasePose(10.05, Eigen::Vector3d::Zero()), "");
  const ObstacleReport fresh = r.monitor.update(10.1);
  ASSERT_EQ(fresh.status, ObstacleReport::Status::Publish);
  EXPECT_EQ(fresh.stamp, 10.05) << "stamped with the newest state";
  ASSERT_FALSE(fresh.distances.empty());
  EXPECT_EQ(fresh.distances.front().link, "base_link");
  EXPECT_NEAR(fresh.distances.front().distance, 0.15, 0.03);
  // The older of the two becomes stale: nothing.
  EXPECT_EQ(r.monitor.update(10.2001).status, ObstacleReport::Status::StateStale);
  EXPECT_STREQ(toString(ObstacleReport::Status::StateStale), "state_stale");
  // Rejected inputs do not refresh the state.
  EXPECT_NE(r.monitor.setJointState(10.2, r.robot.arm_joints, {0, 0, kNaN, 0, 0, 0}).find("NaN"), std::string::npos);
  EXPECT_NE(r.monitor.setJointState(10.2, {"joint1"}, {0.0}).find("lacks arm joint"), std::string::npos);
  EXPECT_NE(r.monitor.setJointState(10.2, r.robot.arm_joints, {0.0}).find("positions"), std::string::npos);
  EXPECT_NE(r.monitor.setBasePose(10.2, Eigen::Vector3d(0, kNaN, 0)), "");
  EXPECT_EQ(r.monitor.update(10.21).status, ObstacleReport::Status::StateStale);
  r.state(10.2);
  EXPECT_EQ(r.monitor.update(10.21).status, ObstacleReport::Status::Publish);
}

TEST(ObstacleMonitor, ExclusionListsHideObstaclesUntilTheyExpire) {
  Rig r;
  r.addBlock();
  const ExclusionZone around_block{Eigen::Vector3d(0.43, 0.0, 0.23), 0.1};
  ASSERT_EQ(r.monitor.setExclusionZones(1.0, {around_block}), "");
  EXPECT_NE(r.monitor.setExclusionZones(1.1, {{Eigen::Vector3d(kNaN, 0, 0), 0.1}}), "");
  EXPECT_EQ(r.monitor.field().exclusionZones().size(), 1u) << "a rejected list keeps the previous one";
  r.state(1.4);
  ObstacleReport rep = r.monitor.update(1.45);
  ASSERT_EQ(rep.status, ObstacleReport::Status::Publish);
  EXPECT_TRUE(rep.distances.empty()) << "the only obstacle is excluded";
  EXPECT_FALSE(rep.exclusions_expired);
  // 0.5 s after the list: dropped, the block counts again.
  r.state(1.55);
  rep = r.monitor.update(1.5501);
  ASSERT_EQ(rep.status, ObstacleReport::Status::Publish);
  EXPECT_TRUE(rep.exclusions_expired);
  EXPECT_FALSE(rep.distances.empty());
  EXPECT_TRUE(r.monitor.field().exclusionZones().empty());
  rep = r.monitor.update(1.56);
  EXPECT_FALSE(rep.exclusions_expired) << "reported once";
}

TEST(ObstacleMonitor, CloudInsertionsAreRateLimited) {
  Rig r;  // 5 Hz
  EXPECT_TRUE(r.monitor.acceptCloud(100.0));
  EXPECT_FALSE(r.monitor.acceptCloud(100.1));
  EXPECT_FALSE(r.monitor.acceptCloud(100.199));
  EXPECT_TRUE(r.monitor.acceptCloud(100.2));
  EXPECT_TRUE(r.monitor.acceptCloud(50.0)) << "clock jumped back (simulator reset)";
  EXPECT_FALSE(r.monitor.acceptCloud(50.1));
}

TEST(ObstacleMonitor, OwnPointsAreRemovedOnlyWithAFreshState) {
  Rig r;
  // Points on the base cylinder, seen from 1 m in front.
  PointList on_base;
  for (double z = 0.1; z < 0.55; z += 0.05) on_base.emplace_back(0.25f, 0.0f, static_cast<float>(z));
  const Eigen::Vector3d origin(1.0, 0.0, 0.5);
  ObstacleMonitor::CloudInsertion ins = r.monitor.insertCloud(5.0, on_base, origin);
  EXPECT_FALSE(ins.self_filtered);
  EXPECT_EQ(ins.stats.robot, 0);
  EXPECT_EQ(ins.stats.inserted, static_cast<int>(on_base.size()));
  r.monitor.field().clear();
  r.state(5.0);
  ins = r.monitor.insertCloud(5.1, on_base, origin);
  EXPECT_TRUE(ins.self_filtered);
  EXPECT_EQ(ins.stats.robot, static_cast<int>(on_base.size()));
  EXPECT_EQ(ins.stats.inserted, 0);
}

TEST(ObstacleMonitor, ParamsAndLinksAreValidated) {
  const auto robot = ehc_control::loadRobotConfig(test::robotYaml());
  ObstacleMapConfig map;
  map.links.push_back("no_such_link");
  EXPECT_THROW(ObstacleMonitor(robot, map, ObstacleMonitorParams()), std::invalid_argument);
  try {
    loadObstacleMonitorParams(ConfigNode::loadString("node: {max_insert_rate_hz: 0}\n", "obst.yaml",
                                                                  "ObstacleNode").child("node"));
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("max_insert_rate_hz"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("obst.yaml"), std::string::npos) << e.what();
  }
  const ObstacleMonitorParams p = loadObstacleMonitorParams(
      ConfigNode::loadString("node: {state_timeout: 0.3}\n", "obst.yaml", "ObstacleNode").child("node"));
  EXPECT_EQ(p.state_timeout, 0.3);
  EXPECT_EQ(p.exclusion_timeout, 0.5);
}


TEST(ObstacleMonitor, AFullD435FrameIsBoundedByVoxelDecimationAndThePointBudget) {
  Rig r;
  const PointList frame = test::fullD435Wall();
  ASSERT_EQ(frame.size(), 307200u);
  const ObstacleMonitorParams& p = r.monitor.params();
  // Voxel step: one point per 2 cm voxel; the wall (1.56 x 1.17 m at 1.5 m) has about 4 600.
  int after_voxel = 0;
  const PointList bounded = r.monitor.boundCloud(frame, &after_voxel);
  EXPECT_GT(after_voxel, 3000);
  EXPECT_LT(after_voxel, 10000);
  EXPECT_LE(static_cast<int>(bounded.size()), p.max_cloud_points);
  EXPECT_EQ(static_cast<int>(bounded.size()), std::min(after_voxel, p.max_cloud_points));
  // Deterministic, and every kept point is one of the frame's.
  EXPECT_EQ(r.monitor.boundCloud(frame), bounded);
  // The insertion inserts the bounded cloud only, and the wall is in the map.
  r.state(1.0);
  const ObstacleMonitor::CloudInsertion ins = r.monitor.insertCloud(1.0, frame, Eigen::Vector3d(0.0, 0.0, 1.0));
  EXPECT_EQ(ins.received, 307200);
  EXPECT_EQ(ins.after_voxel, after_voxel);
  EXPECT_EQ(ins.stats.input, static_cast<int>(bounded.size()));
  EXPECT_GT(r.monitor.field().occupiedLeafCount(), static_cast<std::size_t>(bounded.size() / 2));
  // A budget smaller than the decimated cloud: an even stride, at most the budget.
  ObstacleMonitorParams small;
  small.max_cloud_points = 100;
  ObstacleMonitor tight(r.robot, ObstacleMapConfig(), small);
  EXPECT_EQ(tight.boundCloud(frame).size(), 100u);
  // Non-finite points never count; voxel decimation off keeps every finite point (up to the budget).
  ObstacleMonitorParams off;
  off.cloud_voxel = 0.0;
  off.max_cloud_points = 1000000;
  ObstacleMonitor raw(r.robot, ObstacleMapConfig(), off);
  PointList with_nan = {Eigen::Vector3f(1, 0, 1), Eigen::Vector3f(std::nanf(""), 0, 1), Eigen::Vector3f(1, 0, 1)};
  EXPECT_EQ(raw.boundCloud(with_nan).size(), 2u);
  EXPECT_EQ(r.monitor.boundCloud(with_nan).size(), 1u);  // the same voxel twice
  // Parameters: the budget must be positive and is read from the node mapping.
  EXPECT_THROW(loadObstacleMonitorParams(ConfigNode::loadString("node: {max_cloud_points: 0}\n",
                                                                             "obst.yaml", "ObstacleNode").child("node")),
               std::invalid_argument);
  const ObstacleMonitorParams q = loadObstacleMonitorParams(ConfigNode::loadString(
      "node: {cloud_voxel: 0.05, max_cloud_points: 500}\n", "obst.yaml", "ObstacleNode").child("node"));
  EXPECT_EQ(q.cloud_voxel, 0.05);
  EXPECT_EQ(q.max_cloud_points, 500);
}

TEST(ObstacleMonitor, TheWorkPerCloudIsBoundedByThePointBudgetWhateverItsSize) {
  Rig r;
  r.state(1.0);
  const ObstacleMonitorParams& p = r.monitor.params();
  // A 1920x1080 depth frame (2 073 600 points) of a block in front of the base: the point budget
  // first, then the voxel grid and the insertion budget.
  const test::Box block{test::pose(0.43, 0.0, 0.23, 0.3), Eigen::Vector3d(0.06, 0.06, 0.06)};
  const Eigen::Isometry3d cam = test::lookAt(Eigen::Vector3d(0.1, 0.0, 1.0), Eigen::Vector3d(0.5, 0.0, 0.2));
  const PointList frame = test::depthCameraCloud(1920, 1080, cam, {block});
  const ObstacleMonitor::CloudInsertion big = r.monitor.queueCloud(1.0, frame, cam.translation());
  EXPECT_EQ(big.received, 2073600);
  EXPECT_EQ(big.after_budget, p.max_input_points);
  EXPECT_LE(big.after_voxel, big.after_budget);
  EXPECT_LE(big.queued, p.max_cloud_points);
  // Random cloud sizes up to 3 M points: the points past the voxel step never exceed the budget.
  const unsigned seed = 3;
  std::printf("seed %u\n", seed);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> size(1, 3000000);
  std::uniform_real_distribution<float> u(-3.0f, 3.0f);
  for (int k = 0; k < 4; ++k) {
    PointList cloud(static_cast<std::size_t>(size(rng)));
    for (auto& q : cloud) q = Eigen::Vector3f(u(rng), u(rng), 0.5f * (u(rng) + 3.0f));
    const ObstacleMonitor::CloudInsertion c = r.monitor.queueCloud(1.0, cloud, cam.translation());
    EXPECT_EQ(c.after_budget, std::min(c.received, p.max_input_points)) << c.received << " points";
    EXPECT_LE(c.queued, p.max_cloud_points);
  }
}

TEST(ObstacleMonitor, AFrameReadWithinThePointBudgetGivesTheSameDistances) {
  // A 1280x720 frame (921 600 points) of blocks around the robot, read as the node reads it
  // (PointBudget: every 4th row and column, 57 600 points) and whole: each link within the
  // influence distance in either map is within one map voxel (2 cm) of the same distance in the
  // other (or, missing there, within 2 cm of the influence distance). Every voxel point is
  // inserted (max_cloud_points, the insertion budget, off): the read budget's effect alone.
  // Random blocks and views (seed printed).
  const unsigned seed = 5;
  std::printf("seed %u\n", seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ObstacleMonitorParams budgeted_params;
  budgeted_params.max_cloud_points = 1000000;
  const ObstacleMonitorParams& budgeted = budgeted_params;
  const double influence = ObstacleMapConfig().influence_distance;
  ObstacleMonitorParams whole_params = budgeted;
  whole_params.max_input_points = 10000000;
  const ObstacleMonitorParams& whole = whole_params;
  for (int k = 0; k < 4; ++k) {
    std::vector<test::Box> blocks;
    for (int b = 0; b < 3; ++b) {
      const double a = -0.8 + 1.6 * u(rng), d = 0.4 + 0.15 * u(rng);
      blocks.push_back({test::pose(d * std::cos(a), d * std::sin(a), 0.1 + 0.4 * u(rng), M_PI * u(rng)),
                        Eigen::Vector3d(0.05 + 0.1 * u(rng), 0.05 + 0.1 * u(rng), 0.05 + 0.1 * u(rng))});
    }
    const Eigen::Isometry3d cam = test::lookAt(Eigen::Vector3d(0.2 * u(rng), 0.0, 1.1 + 0.3 * u(rng)),
                                               Eigen::Vector3d(0.6, -0.3 + 0.6 * u(rng), 0.2));
    const PointList frame = test::depthCameraCloud(1280, 720, cam, blocks, 0.002, seed + k);
    const CloudPoints read = test::packCloud(frame, test::xyzFloat32(), 720).extract(
        static_cast<std::size_t>(budgeted.max_input_points));
    ASSERT_EQ(read.read, 57600u);
    std::vector<std::vector<LinkObstacleDistance>> out;
    for (const auto& [params, cloud] : {std::make_pair(&whole, &frame), std::make_pair(&budgeted, &read.points)}) {
      Rig r;
      ObstacleMonitor m(r.robot, ObstacleMapConfig(), *params);
      ASSERT_EQ(m.setJointState(1.0, r.robot.arm_joints, r.ready()), "");
      ASSERT_EQ(m.setBasePose(1.0, Eigen::Vector3d::Zero()), "");
      m.insertCloud(1.0, *cloud, cam.translation());
      const ObstacleReport rep = m.update(1.0);
      ASSERT_EQ(rep.status, ObstacleReport::Status::Publish);
      out.push_back(rep.distances);
    }
    SCOPED_TRACE("scene " + std::to_string(k));
    for (int a = 0; a < 2; ++a)
      for (const LinkObstacleDistance& d : out[static_cast<std::size_t>(a)]) {
        double other = influence;  // not reported: beyond the influence distance
        for (const LinkObstacleDistance& e : out[static_cast<std::size_t>(1 - a)])
          if (e.link == d.link) other = e.distance;
        EXPECT_NEAR(d.distance, other, 0.02) << d.link << (a == 0 ? " (whole frame)" : " (budget)");
        std::printf("scene %d %s %s: %.4f / %.4f m\n", k, a == 0 ? "whole" : "budget", d.link.c_str(), d.distance, other);
      }
  }
}

TEST(ObstacleMonitor, AQueuedCloudIsRayCastInBoundedChunksPerUpdate) {
  Rig r;
  r.state(1.0);
  const PointList frame = test::fullD435Wall();
  const ObstacleMonitor::CloudInsertion q = r.monitor.queueCloud(1.0, frame, Eigen::Vector3d(0.0, 0.0, 1.0));
  const int budget = r.monitor.params().points_per_update;
  EXPECT_EQ(q.queued, r.monitor.params().max_cloud_points);
  EXPECT_EQ(q.replaced, 0);
  EXPECT_TRUE(q.self_filtered);
  EXPECT_EQ(r.monitor.field().occupiedLeafCount(), 0u);  // queued, nothing cast yet
  // Each update casts at most points_per_update; the distances are computed every time.
  int updates = 0;
  while (r.monitor.queuedPoints() > 0) {
    const ObstacleReport rep = r.monitor.update(1.0 + 0.02 * ++updates);
    EXPECT_LE(rep.inserted.input, budget);
    EXPECT_EQ(rep.status, ObstacleReport::Status::Publish);
    r.state(1.0 + 0.02 * updates);
    ASSERT_LT(updates, 1000);
  }
  EXPECT_EQ(updates, (q.queued + budget - 1) / budget);
  EXPECT_GT(r.monitor.field().occupiedLeafCount(), static_cast<std::size_t>(q.queued / 2));
  EXPECT_EQ(r.monitor.update(2.0).inserted.input, 0);  // nothing left
  // A newer cloud replaces an unfinished one.
  r.monitor.queueCloud(2.0, frame, Eigen::Vector3d(0.0, 0.0, 1.0));
  r.monitor.update(2.0);
  const ObstacleMonitor::CloudInsertion q2 = r.monitor.queueCloud(2.0, frame, Eigen::Vector3d(0.0, 0.0, 1.0));
  EXPECT_EQ(q2.replaced, q.queued - budget);
  EXPECT_THROW(r.monitor.queueCloud(2.0, frame, Eigen::Vector3d(std::nan(""), 0.0, 1.0)), std::invalid_argument);
}

namespace {

constexpr StampNs kMs = 1000000;

TEST(ObstacleLockstepCycle, AStateIsCompleteOnceJointsAndOdometryOfOneStampAreIn) {
  ObstacleLockstepCycle c(50.0);
  EXPECT_FALSE(c.jointState(1000 * kMs));
  EXPECT_FALSE(c.odometry(980 * kMs));  // another stamp: not a pair
  auto s = c.odometry(1000 * kMs);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->stamp, 1000 * kMs);
  EXPECT_TRUE(s->publish);  // the first state publishes
  // Odometry first works too.
  EXPECT_FALSE(c.odometry(1020 * kMs));
  s = c.jointState(1020 * kMs);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->stamp, 1020 * kMs);
  // A zero stamp never completes a state.
  ObstacleLockstepCycle z(50.0);
  EXPECT_FALSE(z.jointState(0));
  EXPECT_FALSE(z.odometry(0));
}

TEST(ObstacleLockstepCycle, EachJointStateCompletesAtMostOneState) {
  ObstacleLockstepCycle c(50.0);
  c.jointState(1000 * kMs);
  ASSERT_TRUE(c.odometry(1000 * kMs));
  EXPECT_FALSE(c.odometry(1000 * kMs));  // a repeated odometry: the joint state was used
  EXPECT_TRUE(c.jointState(1000 * kMs));  // a repeated joint state pairs with the odometry again
}

TEST(ObstacleLockstepCycle, DistancesAreDueAtThePublishRateOfTheStamps) {
  ObstacleLockstepCycle c(50.0);  // every 20 ms of stamps
  std::vector<StampNs> published;
  for (StampNs t = 1000 * kMs; t <= 1100 * kMs; t += 6 * kMs) {  // states every 6 ms
    c.jointState(t);
    const auto s = c.odometry(t);
    ASSERT_TRUE(s);
    if (s->publish) published.push_back(t);
  }
  // The first state at least 20 ms after the last published one.
  EXPECT_EQ(published, (std::vector<StampNs>{1000 * kMs, 1024 * kMs, 1048 * kMs, 1072 * kMs, 1096 * kMs}));
}

TEST(ObstacleLockstepCycle, AStateStampedBeforeThePreviousOneRestartsTheRate) {
  ObstacleLockstepCycle c(50.0);
  c.jointState(5000 * kMs);
  EXPECT_TRUE(c.odometry(5000 * kMs)->publish);
  c.jointState(5010 * kMs);
  EXPECT_FALSE(c.odometry(5010 * kMs)->publish);  // 10 ms after the last published
  // Simulator reset: 5005 ms is before the previous state (5010) though 5 ms after the last
  // published one; the rate restarts, so it publishes.
  c.jointState(5005 * kMs);
  EXPECT_TRUE(c.odometry(5005 * kMs)->publish);
  c.jointState(5015 * kMs);
  EXPECT_FALSE(c.odometry(5015 * kMs)->publish);
  EXPECT_THROW(ObstacleLockstepCycle(0.0), std::invalid_argument);
}

}  // namespace
