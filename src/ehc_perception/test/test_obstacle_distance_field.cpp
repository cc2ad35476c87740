// ObstacleDistanceField (OctoMap + FCL) on ehc_control::RobotCollisionModel (URDF collisions;
// the model itself: ehc_control/test/test_robot_collision_model): distances against analytic
// values, free-space clearing by rays, self filtering, the RealMan robot with its fingers fully
// open, bad inputs and configs; octreeShapeDistance against fcl::distance.
#include "ehc_common/config_node.h"
#include "ehc_control/whole_body_model.h"
#include "ehc_perception/obstacle_distance_field.h"
#include "ehc_perception/octree_shape_distance.h"
#include "ehc_test/perception_fixtures.h"
#include "ehc_test/test_seed.h"

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/distance.h>
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

using namespace ehc_perception;
using ehc_control::RobotCollisionModel;
using ehc_perception::test::pose;

namespace {

/// Probe "robot": a sphere (r 0.05), a box (0.10 x 0.06 x 0.04) and a cylinder (r 0.03,
/// length 0.20), each on its own link; the tests pose the links directly.
const char* kProbeUrdf = R"(<?xml version="1.0"?>
<robot name="probe">
  <link name="ball"><collision><geometry><sphere radius="0.05"/></geometry></collision></link>
  <link name="block"><collision><geometry><box size="0.10 0.06 0.04"/></geometry></collision></link>
  <link name="rod"><collision><origin xyz="0 0 0.1" rpy="0 0 0"/>
    <geometry><cylinder radius="0.03" length="0.20"/></geometry></collision></link>
  <link name="mesh"><collision><geometry><mesh filename="package://x/y.stl"/></geometry></collision></link>
  <link name="bare"/>
  <joint name="j1" type="fixed"><parent link="ball"/><child link="block"/></joint>
  <joint name="j2" type="fixed"><parent link="ball"/><child link="rod"/></joint>
  <joint name="j3" type="fixed"><parent link="ball"/><child link="mesh"/></joint>
  <joint name="j4" type="fixed"><parent link="ball"/><child link="bare"/></joint>
</robot>)";

ObstacleMapConfig probeConfig() {
  ObstacleMapConfig c;
  c.resolution = 0.02;
  c.influence_distance = 0.3;
  c.min_height = -1.0;
  c.links = {"ball", "block", "rod"};
  return c;
}

struct Probe {
  RobotCollisionModel robot{kProbeUrdf, {}, {"ball", "block", "rod"}};
  ObstacleDistanceField field{probeConfig(), robot};
  Eigen::Isometry3d far = pose(-5, -5, 5, 0);
  /// Link poses: only `link` is near, the others far away.
  std::vector<Eigen::Isometry3d> place(const std::string& link, const Eigen::Isometry3d& T) {
    std::vector<Eigen::Isometry3d> p;
    for (const auto& l : robot.links()) p.push_back(l.name == link ? T : far);
    return p;
  }
  const LinkObstacleDistance* find(const std::vector<LinkObstacleDistance>& ds,
                                   const std::string& link) {
    for (const auto& d : ds)
      if (d.link == link) return &d;
    return nullptr;
  }
};

void expectConsistent(const LinkObstacleDistance& d) {
  EXPECT_NEAR(d.normal.norm(), 1.0, 1e-9);
  if (d.distance > 1e-6) {
    EXPECT_NEAR((d.link_point - d.obstacle_point).norm(), d.distance, 1e-6);
    EXPECT_LT((d.link_point - d.obstacle_point - d.distance * d.normal).norm(), 1e-6);
  }
}

}  // namespace

TEST(ObstacleDistanceField, DistancesMatchAnalyticValuesWithinHalfAVoxel) {
  Probe p;
  const double tol = 0.5 * 0.02 + 1e-4;
  // Grid-aligned obstacle box [0.40, 0.60] x [-0.20, 0.20] x [0.00, 0.40].
  p.field.addOccupiedBox(Eigen::Vector3d(0.40, -0.20, 0.0), Eigen::Vector3d(0.60, 0.20, 0.40));
  EXPECT_EQ(p.field.occupiedLeafCount(), 10u * 20u * 20u);
  EXPECT_EQ(p.field.cell(Eigen::Vector3d(0.5, 0, 0.2)), ObstacleDistanceField::Cell::Occupied);
  EXPECT_EQ(p.field.cell(Eigen::Vector3d(0.3, 0, 0.2)), ObstacleDistanceField::Cell::Unknown);

  // Sphere in front of the x = 0.40 face.
  auto ds = p.field.distances(p.place("ball", pose(0.25, 0.0, 0.2, 0)));
  const LinkObstacleDistance* d = p.find(ds, "ball");
  ASSERT_NE(d, nullptr);
  EXPECT_NEAR(d->distance, 0.10, tol);
  EXPECT_NEAR(d->link_point.x(), 0.30, tol);
  EXPECT_NEAR(d->obstacle_point.x(), 0.40, tol);
  EXPECT_NEAR(d->normal.x(), -1.0, 0.01);
  expectConsistent(*d);
  EXPECT_EQ(ds.size(), 1u);  // the far links are beyond the influence distance

  // Sphere off the box edge (x = 0.40, y = 0.20): distance to the edge minus the radius.
  ds = p.field.distances(p.place("ball", pose(0.30, 0.30, 0.2, 0)));
  ASSERT_NE(p.find(ds, "ball"), nullptr);
  EXPECT_NEAR(p.find(ds, "ball")->distance, std::sqrt(0.02) - 0.05, tol);
  EXPECT_NEAR(p.find(ds, "ball")->normal.x(), -std::sqrt(0.5), 0.02);
  expectConsistent(*p.find(ds, "ball"));

  // Box above the top face (z = 0.40), turned 90 deg about z: gap 0.50 - 0.02 - 0.40.
  ds = p.field.distances(p.place("block", pose(0.5, 0.0, 0.50, M_PI / 2)));
  ASSERT_NE(p.find(ds, "block"), nullptr);
  EXPECT_NEAR(p.find(ds, "block")->distance, 0.08, tol);
  EXPECT_NEAR(p.find(ds, "block")->normal.z(), 1.0, 0.01);
  expectConsistent(*p.find(ds, "block"));

  // Upright cylinder beside the y = -0.20 face: gap 0.30 - 0.20 - 0.03.
  ds = p.field.distances(p.place("rod", pose(0.5, -0.30, 0.1, 0)));
  ASSERT_NE(p.find(ds, "rod"), nullptr);
  EXPECT_NEAR(p.find(ds, "rod")->distance, 0.07, tol);
  EXPECT_NEAR(p.find(ds, "rod")->normal.y(), -1.0, 0.02);
  expectConsistent(*p.find(ds, "rod"));

  // Beyond the influence distance: omitted.
  EXPECT_TRUE(p.field.distances(p.place("ball", pose(0.0, 0.0, 0.2, 0))).empty());

  // Penetration: reported with distance <= 0 and a finite unit normal.
  ds = p.field.distances(p.place("ball", pose(0.42, 0.0, 0.2, 0)));
  ASSERT_NE(p.find(ds, "ball"), nullptr);
  EXPECT_LE(p.find(ds, "ball")->distance, 0.0);
  EXPECT_TRUE(p.find(ds, "ball")->normal.allFinite());
  EXPECT_NEAR(p.find(ds, "ball")->normal.norm(), 1.0, 1e-9);
}

TEST(ObstacleDistanceField, ExclusionZonesHideTheObjectButNotItsSurroundings) {
  Probe p;
  const double tol = 0.5 * 0.02 + 1e-4;
  // A small "object" (0.06 m cube centred at (0.5, 0, 0.23)) standing on a "table" top
  // [0.3, 0.9] x [-0.3, 0.3] x [0.16, 0.20].
  p.field.addOccupiedBox(Eigen::Vector3d(0.47, -0.03, 0.20), Eigen::Vector3d(0.53, 0.03, 0.26));
  p.field.addOccupiedBox(Eigen::Vector3d(0.30, -0.30, 0.16), Eigen::Vector3d(0.90, 0.30, 0.20));
  const std::size_t leaves = p.field.occupiedLeafCount();
  // Ball (r 0.05) right above the object: the object is the closest obstacle (gap 0.04).
  const auto above = p.place("ball", pose(0.5, 0.0, 0.35, 0));
  auto ds = p.field.distances(above);
  ASSERT_NE(p.find(ds, "ball"), nullptr);
  EXPECT_NEAR(p.find(ds, "ball")->distance, 0.35 - 0.26 - 0.05, tol);

  // The object excluded: the table below it is the closest obstacle (0.35 - 0.20 - 0.05).
  p.field.setExclusionZones({{Eigen::Vector3d(0.5, 0.0, 0.23), 0.05}});
  ds = p.field.distances(above);
  ASSERT_NE(p.find(ds, "ball"), nullptr);
  EXPECT_NEAR(p.find(ds, "ball")->distance, 0.10, tol);
  EXPECT_GT(p.find(ds, "ball")->distance, 0.35 - 0.26 - 0.05 + tol);
  // The map itself is unchanged (the zone only hides voxels from the queries).
  EXPECT_EQ(p.field.occupiedLeafCount(), leaves);
  EXPECT_EQ(p.field.cell(Eigen::Vector3d(0.5, 0.0, 0.23)), ObstacleDistanceField::Cell::Occupied);

  // Cleared: the object is an obstacle again.
  p.field.setExclusionZones({});
  ds = p.field.distances(above);
  ASSERT_NE(p.find(ds, "ball"), nullptr);
  EXPECT_NEAR(p.find(ds, "ball")->distance, 0.04, tol);

  // A zone covering everything: nothing is reported.
  p.field.setExclusionZones({{Eigen::Vector3d(0.6, 0.0, 0.2), 1.0}});
  EXPECT_TRUE(p.field.distances(above).empty());

  // Map updates while a zone is set are seen by the next query (the filtered copy is rebuilt).
  p.field.setExclusionZones({{Eigen::Vector3d(0.5, 0.0, 0.23), 0.05}});
  EXPECT_NEAR(p.find(p.field.distances(above), "ball")->distance, 0.10, tol);
  p.field.addOccupiedBox(Eigen::Vector3d(0.60, -0.03, 0.32), Eigen::Vector3d(0.64, 0.03, 0.38));
  ds = p.field.distances(above);
  ASSERT_NE(p.find(ds, "ball"), nullptr);
  EXPECT_NEAR(p.find(ds, "ball")->distance, 0.10 - 0.05, tol);  // new block at x = 0.60: gap 0.05

  // Bad zones are rejected and leave the zones unchanged.
  const auto before = p.field.exclusionZones();
  EXPECT_THROW(p.field.setExclusionZones({{Eigen::Vector3d(std::nan(""), 0, 0), 0.1}}), std::invalid_argument);
  EXPECT_THROW(p.field.setExclusionZones({{Eigen::Vector3d::Zero(), -0.1}}), std::invalid_argument);
  try {
    p.field.setExclusionZones({{Eigen::Vector3d::Zero(), 2.0}});
    ADD_FAILURE() << "radius 2 m accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("[ObstacleDistanceField] exclusion zone radius"), std::string::npos) << e.what();
  }
  EXPECT_EQ(p.field.exclusionZones(), before);
}

TEST(ObstacleDistanceField, PlannedQueriesTakeTheirOwnZonesAndLeaveTheFieldsUntouched) {
  // distances(poses, zones) answers as the field with those zones set would (a penetration <= 0,
  // unsigned), and changes neither the field's zones nor its next seeded query. Random blocks,
  // zones and link poses.
  std::mt19937 rng(ehc_test::testSeed("ObstacleDistanceField planned queries"));
  std::uniform_real_distribution<double> u(-0.4, 0.4), r(0.0, 0.15), yaw(-M_PI, M_PI);
  for (int trial = 0; trial < 20; ++trial) {
    Probe p, q;  // q: the same map with the zones set on it
    for (int b = 0; b < 6; ++b) {
      const Eigen::Vector3d lo(u(rng), u(rng), u(rng)), size(r(rng), r(rng), r(rng));
      p.field.addOccupiedBox(lo, lo + size);
      q.field.addOccupiedBox(lo, lo + size);
    }
    const std::vector<ExclusionZone> own = {{Eigen::Vector3d(u(rng), u(rng), u(rng)), r(rng)}};
    const std::vector<ExclusionZone> planned = {{Eigen::Vector3d(u(rng), u(rng), u(rng)), r(rng)},
                                                {Eigen::Vector3d(u(rng), u(rng), u(rng)), r(rng)}};
    p.field.setExclusionZones(own);
    q.field.setExclusionZones(planned);
    std::vector<Eigen::Isometry3d> poses;
    for (std::size_t l = 0; l < p.robot.links().size(); ++l) poses.push_back(pose(u(rng), u(rng), u(rng), yaw(rng)));
    const auto before = p.field.distances(poses);
    const auto planned_ds = p.field.distances(poses, planned);
    const auto want = q.field.distances(poses);
    ASSERT_EQ(planned_ds.size(), want.size()) << "trial " << trial;
    for (std::size_t i = 0; i < want.size(); ++i) {
      EXPECT_EQ(planned_ds[i].link, want[i].link);
      if (want[i].distance > 0.0)
        EXPECT_DOUBLE_EQ(planned_ds[i].distance, want[i].distance) << "trial " << trial << " " << want[i].link;
      else  // a penetration: unsigned, no depth
        EXPECT_LE(planned_ds[i].distance, 0.0) << "trial " << trial << " " << want[i].link;
    }
    EXPECT_EQ(p.field.exclusionZones(), own);
    const auto after = p.field.distances(poses);
    ASSERT_EQ(after.size(), before.size());
    for (std::size_t i = 0; i < after.size(); ++i) EXPECT_DOUBLE_EQ(after[i].distance, before[i].distance);
  }
  Probe p;
  EXPECT_THROW(p.field.distances(p.place("ball", pose(0, 0, 0, 0)), {{Eigen::Vector3d::Zero(), 2.0}}), std::invalid_argument);
}

TEST(ObstacleDistanceField, CloudsMarkObstaclesAndRaysClearFreeSpace) {
  Probe p;
  // A wall facing the sensor at (0, 0, 0.4), spanning +-0.3 m around it, scaled by `grow`.
  auto wall = [](double x, double grow) {
    PointList w;
    for (double y = -0.3 * grow; y <= 0.3 * grow; y += 0.01)
      for (double z = 0.4 - 0.3 * grow; z <= 0.4 + 0.3 * grow; z += 0.01)
        w.push_back(Eigen::Vector3f(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)));
    return w;
  };
  const Eigen::Vector3d origin(0.0, 0.0, 0.4);
  const std::uint64_t empty = p.field.revision();
  p.field.setExclusionZones({{Eigen::Vector3d(1.0, 0.0, 0.4), 0.1}});
  p.field.insertCloud({Eigen::Vector3f(1.0f, 0.0f, std::nanf(""))}, origin);  // nothing kept
  EXPECT_EQ(p.field.revision(), empty) << "zones and a cloud without a kept point leave the map as it was";
  p.field.setExclusionZones({});
  const auto st = p.field.insertCloud(wall(1.01, 1.0), origin);
  EXPECT_EQ(st.inserted, st.input);
  EXPECT_GT(p.field.revision(), empty);
  EXPECT_EQ(p.field.cell(Eigen::Vector3d(1.01, 0.0, 0.4)), ObstacleDistanceField::Cell::Occupied);
  EXPECT_EQ(p.field.cell(Eigen::Vector3d(0.5, 0.0, 0.4)), ObstacleDistanceField::Cell::Free);
  EXPECT_EQ(p.field.cell(Eigen::Vector3d(1.5, 0.0, 0.4)), ObstacleDistanceField::Cell::Unknown);

  auto ds = p.field.distances(p.place("ball", pose(0.80, 0.0, 0.4, 0)));
  ASSERT_NE(p.find(ds, "ball"), nullptr);
  EXPECT_NEAR(p.find(ds, "ball")->distance, 1.00 - 0.80 - 0.05, 0.01 + 1e-4);

  // The wall moves back to x = 1.51 (and grows so that its rays cover the old one): the
  // rays through the old wall clear it.
  for (int k = 0; k < 4; ++k) p.field.insertCloud(wall(1.51, 1.6), origin);
  EXPECT_EQ(p.field.cell(Eigen::Vector3d(1.01, 0.0, 0.4)), ObstacleDistanceField::Cell::Free);
  EXPECT_EQ(p.field.cell(Eigen::Vector3d(1.51, 0.0, 0.4)), ObstacleDistanceField::Cell::Occupied);
  EXPECT_TRUE(p.field.distances(p.place("ball", pose(0.80, 0.0, 0.4, 0))).empty());
  ds = p.field.distances(p.place("ball", pose(1.30, 0.0, 0.4, 0)));
  ASSERT_NE(p.find(ds, "ball"), nullptr);
  EXPECT_NEAR(p.find(ds, "ball")->distance, 1.50 - 1.30 - 0.05, 0.01 + 1e-4);

  const std::uint64_t walls = p.field.revision();
  p.field.clear();
  EXPECT_GT(p.field.revision(), walls);
  EXPECT_EQ(p.field.occupiedLeafCount(), 0u);
  EXPECT_TRUE(p.field.distances(p.place("ball", pose(1.30, 0.0, 0.4, 0))).empty());
}

TEST(ObstacleDistanceField, FiltersBadPointsFloorAndTheRobotItself) {
  ObstacleMapConfig cfg = probeConfig();
  cfg.min_height = 0.03;
  const RobotCollisionModel robot(kProbeUrdf, {}, cfg.links);
  ObstacleDistanceField field(cfg, robot);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  PointList pts = {Eigen::Vector3f(nan, 0, 0.5), Eigen::Vector3f(1.0f, 0.0f, 0.01f)};
  // Points on the ball (link at (0.5, 0, 0.5)): the robot's own surface.
  for (int i = 0; i < 20; ++i) {
    const double a = 0.3 * i;
    pts.push_back(Eigen::Vector3f(0.5f + 0.05f * std::cos(a), 0.05f * std::sin(a), 0.5f));
  }
  pts.push_back(Eigen::Vector3f(1.0f, 0.3f, 0.5f));  // a real obstacle
  std::vector<Eigen::Isometry3d> links = {pose(0.5, 0, 0.5, 0), pose(-5, -5, 5, 0), pose(-5, 5, 5, 0)};
  const auto st = field.insertCloud(pts, Eigen::Vector3d(0, 0, 1.0), &links);
  EXPECT_EQ(st.input, 23);
  EXPECT_EQ(st.non_finite, 1);
  EXPECT_EQ(st.below_min_height, 1);
  EXPECT_EQ(st.robot, 20);
  EXPECT_EQ(st.inserted, 1);
  EXPECT_EQ(field.occupiedLeafCount(), 1u);

  EXPECT_THROW(field.insertCloud(pts, Eigen::Vector3d(0, std::nan(""), 0)), std::invalid_argument);
  std::vector<Eigen::Isometry3d> two = {pose(0, 0, 0, 0), pose(0, 0, 0, 0)};
  EXPECT_THROW(field.insertCloud(pts, Eigen::Vector3d::Zero(), &two), std::invalid_argument);
  EXPECT_THROW(field.distances(two), std::invalid_argument);
  links[0].translation().x() = std::nan("");
  EXPECT_THROW(field.distances(links), std::invalid_argument);
  EXPECT_THROW(field.addOccupiedBox(Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(0, 0, 0)),
               std::invalid_argument);
}

TEST(ObstacleDistanceField, RealManRobotNextToATable) {
  const ehc_control::WholeBodyModel model(
      ehc_control::loadRobotConfig(ehc_perception::test::robotYaml()));
  ObstacleMapConfig cfg;
  const RobotCollisionModel robot(model.urdfXml(), model.config().arm_joints, model.config().checked_links);
  EXPECT_EQ(robot.links().size(), 12u);
  ObstacleDistanceField field(cfg, robot);
  // Table top 0.66-0.70 m high, front edge 0.10 m ahead of the base cylinder (r 0.25).
  field.addOccupiedBox(Eigen::Vector3d(0.36, -0.6, 0.66), Eigen::Vector3d(1.2, 0.6, 0.70));
  const Eigen::VectorXd q = model.config().arm_ready;
  const auto poses = field.linkPoses(model, Eigen::Vector3d::Zero(), q);
  ASSERT_EQ(poses.size(), 12u);
  const auto ds = field.distances(poses);
  ASSERT_FALSE(ds.empty());
  bool base_found = false;
  for (const auto& d : ds) {
    expectConsistent(d);
    EXPECT_LE(d.distance, cfg.influence_distance);
    if (d.link == "base_link") {
      base_found = true;
      // Base cylinder top at 0.60 m, radius 0.25: closest table point is its front-bottom edge
      // (0.36, 0, 0.66): distance hypot(0.11, 0.06).
      EXPECT_NEAR(d.distance, std::hypot(0.11, 0.06), 0.011);
    }
  }
  EXPECT_TRUE(base_found);
  // Moving the base back by 1 m takes everything out of range.
  EXPECT_TRUE(field.distances(field.linkPoses(model, Eigen::Vector3d(-1.0, 0, 0), q)).empty());
  EXPECT_THROW(field.linkPoses(model, Eigen::Vector3d::Zero(), Eigen::VectorXd::Zero(3)),
               std::invalid_argument);
}

TEST(ObstacleDistanceField, FingersAreModelledFullyOpen) {
  // WholeBodyModel holds the finger joints at 0 (closed); the sim and the real gripper open
  // them 35 mm each during the approach. The obstacle field must see the open fingers.
  const ehc_control::WholeBodyModel model(
      ehc_control::loadRobotConfig(ehc_perception::test::robotYaml()));
  ObstacleMapConfig cfg;
  const RobotCollisionModel robot(model.urdfXml(), model.config().arm_joints, cfg.links);
  ObstacleDistanceField field(cfg, robot);
  const Eigen::VectorXd q = model.config().arm_ready;
  const auto poses = field.linkPoses(model, Eigen::Vector3d::Zero(), q);
  // An explicit opening poses the fingers there (0: closed, where WholeBodyModel puts them).
  const auto closed = field.linkPoses(model, Eigen::Vector3d::Zero(), q, 0.0);
  const Eigen::Isometry3d grip = model.fk(Eigen::Vector3d::Zero(), q, "gripper_base_link");
  for (std::size_t i = 0; i < robot.links().size(); ++i) {
    const std::string& l = robot.links()[i].name;
    const Eigen::Isometry3d held = model.fk(Eigen::Vector3d::Zero(), q, l);
    EXPECT_TRUE(closed[i].isApprox(held, 1e-12)) << l;
    if (l == "left_finger_link" || l == "right_finger_link") {
      const double sign = l == "left_finger_link" ? 1.0 : -1.0;  // URDF axes +y / -y of the gripper
      EXPECT_TRUE((poses[i].translation() - held.translation()).isApprox(sign * 0.035 * grip.linear().col(1), 1e-9))
          << l << ": " << (poses[i].translation() - held.translation()).transpose();
      EXPECT_TRUE(poses[i].linear().isApprox(held.linear(), 1e-12));
    } else {
      EXPECT_TRUE(poses[i].isApprox(held, 1e-12)) << l;
    }
  }
  // One 2 cm obstacle voxel around a point 25 mm beyond the open left finger's outer face: its
  // nearest face is 5-25 mm from the open finger (60 mm from the closed one).
  std::size_t left = 0;
  while (robot.links()[left].name != "left_finger_link") ++left;
  const Eigen::Vector3d p = poses[left] * Eigen::Vector3d(0, 0.010 + 0.025, 0.025);
  const double r = cfg.resolution;
  const Eigen::Vector3d c = ((p / r).array().floor() + 0.5).matrix() * r;  // its voxel's centre
  field.addOccupiedBox(c, c);
  ASSERT_EQ(field.occupiedLeafCount(), 1u);
  const auto ds = field.distances(poses);
  bool found = false;
  for (const auto& d : ds)
    if (d.link == "left_finger_link") {
      found = true;
      EXPECT_LT(d.distance, 0.035) << "open finger not modelled";
      EXPECT_GT(d.distance, 0.0);
    }
  EXPECT_TRUE(found);
  EXPECT_NE(field.summary().find("left_finger_link (finger joint"), std::string::npos) << field.summary();
  EXPECT_NE(field.summary().find("fingers posed at their upper limit (fully open)"), std::string::npos)
      << field.summary();
}

TEST(ObstacleDistanceField, ConfigValidationNamesTheField) {
  auto expectFails = [](const std::string& yaml, const std::string& needle) {
    const auto n = ehc_common::ConfigNode::loadString(yaml, "obst.yaml", "ObstacleDistanceField");
    try {
      loadObstacleMapConfig(n.childOrEmpty("obstacle_map"));
      ADD_FAILURE() << yaml;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("obst.yaml"), std::string::npos) << e.what();
    }
  };
  expectFails("obstacle_map: {resolution: 0.5}", "resolution");
  expectFails("obstacle_map: {prob_hit: 0.3}", "prob_hit");
  expectFails("obstacle_map: {influence_distance: 0.001}", "influence_distance");
  // Robot links are robot-specific: robot.yaml's robot.collision.checked_links, never this file.
  expectFails("obstacle_map: {links: [base_link]}", "robot.collision.checked_links");
  const auto ok = ehc_common::ConfigNode::loadString(
      "obstacle_map: {resolution: 0.05}", "ok.yaml", "ObstacleDistanceField");
  const ObstacleMapConfig c = loadObstacleMapConfig(ok.child("obstacle_map"));
  EXPECT_DOUBLE_EQ(c.resolution, 0.05);
  EXPECT_TRUE(c.links.empty());  // = the robot's checked links
}

// octreeShapeDistance skips only voxels that cannot lower the minimum, so it must give FCL's
// answer exactly: random maps (scattered voxels, slabs, pruned blocks; point clouds with rays),
// random boxes, cylinders and spheres at random poses and random starting bounds; with exclusion
// zones, FCL's answer on the map's copy without the excluded voxels.
namespace {

struct RandomQueries {
  explicit RandomQueries(unsigned seed) : rng(seed) {}
  std::mt19937 rng;
  double in(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }

  /// A map as the field builds it: point clouds (a table-like slab and random boxes' surfaces)
  /// inserted with rays from a sensor above, pruned as OctoMap keeps it.
  std::shared_ptr<octomap::OcTree> cloudMap() {
    auto tree = std::make_shared<octomap::OcTree>(in(0.01, 0.05));
    octomap::Pointcloud pc;
    const double z = in(0.0, 0.3);
    for (double x = -0.4; x < 0.4; x += 0.005)
      for (double y = -0.3; y < 0.3; y += 0.005) pc.push_back(x, y, z);
    for (int b = 0; b < 4; ++b) {
      const Eigen::Vector3d c(in(-0.3, 0.3), in(-0.2, 0.2), z + in(0.02, 0.2));
      const double h = in(0.02, 0.08);
      for (int k = 0; k < 400; ++k) pc.push_back(c.x() + in(-h, h), c.y() + in(-h, h), c.z() + h);
    }
    for (int rep = 0; rep < 3; ++rep)  // repeated: voxels saturate and prune into blocks
      tree->insertPointCloud(pc, octomap::point3d(in(-0.5, 0.5), in(-0.5, 0.5), 1.2), 3.0, false, true);
    return tree;
  }
  /// Scattered voxels and a slab set voxel by voxel (leaves of differing values).
  std::shared_ptr<octomap::OcTree> voxelMap() {
    auto tree = std::make_shared<octomap::OcTree>(in(0.01, 0.05));
    for (int i = 0; i < 300; ++i) tree->updateNode(octomap::point3d(in(-0.5, 0.5), in(-0.5, 0.5), in(-0.2, 0.6)), true);
    const double z = in(-0.1, 0.4);
    for (double x = -0.4; x < 0.4; x += tree->getResolution())
      for (double y = -0.3; y < 0.3; y += tree->getResolution())
        for (int k = 0; k < 4; ++k) tree->updateNode(octomap::point3d(x, y, z), true);
    tree->updateInnerOccupancy();
    return tree;
  }
  std::shared_ptr<fcl::CollisionGeometry<double>> shape(int kind) {
    std::shared_ptr<fcl::CollisionGeometry<double>> g;
    switch (kind % 3) {
      case 0: g = std::make_shared<fcl::Box<double>>(in(0.01, 0.3), in(0.01, 0.3), in(0.01, 0.3)); break;
      case 1: g = std::make_shared<fcl::Cylinder<double>>(in(0.01, 0.08), in(0.02, 0.4)); break;
      default: g = std::make_shared<fcl::Sphere<double>>(in(0.01, 0.1)); break;
    }
    g->computeLocalAABB();
    return g;
  }
  fcl::Transform3<double> pose() {
    fcl::Transform3<double> tf = fcl::Transform3<double>::Identity();
    tf.linear() = Eigen::Quaterniond(Eigen::Vector4d(in(-1, 1), in(-1, 1), in(-1, 1), in(-1, 1)).normalized())
                      .toRotationMatrix();
    tf.translation() = Eigen::Vector3d(in(-0.7, 0.7), in(-0.7, 0.7), in(-0.3, 0.9));
    return tf;
  }
};

/// octreeShapeDistance (with `exclusion`, if given) against fcl::distance on `reference`; returns
/// whether a voxel was found.
bool expectSameAsFcl(const fcl::OcTree<double>& tree, const fcl::OcTree<double>& reference,
                     const fcl::CollisionGeometry<double>& shape, const fcl::Transform3<double>& tf, double bound,
                     const OcTreeExclusion* exclusion) {
  fcl::DistanceRequest<double> req;
  req.enable_nearest_points = true;
  req.enable_signed_distance = true;
  fcl::DistanceResult<double> ours, fcls;
  ours.min_distance = fcls.min_distance = bound;
  for (auto* r : {&ours, &fcls}) r->nearest_points[0] = r->nearest_points[1] = Eigen::Vector3d::Zero();
  octreeShapeDistance(tree, shape, tf, req, &ours, exclusion);
  fcl::distance(&reference, fcl::Transform3<double>::Identity(), &shape, tf, req, fcls);
  EXPECT_EQ(ours.min_distance, fcls.min_distance);
  EXPECT_EQ(ours.nearest_points[0], fcls.nearest_points[0]);
  EXPECT_EQ(ours.nearest_points[1], fcls.nearest_points[1]);
  return fcls.o1 != nullptr;
}

}  // namespace

TEST(OctreeShapeDistance, EqualsFclDistanceBitForBit) {
  const unsigned seed = ehc_test::testSeed("OctreeShapeDistance against FCL");
  RandomQueries r(seed);
  int found = 0, queries = 0;
  for (int map = 0; map < 8; ++map) {
    const std::shared_ptr<octomap::OcTree> tree = map % 2 ? r.cloudMap() : r.voxelMap();
    const fcl::OcTree<double> octree(std::static_pointer_cast<const octomap::OcTree>(tree));
    for (int q = 0; q < 60; ++q, ++queries) {
      SCOPED_TRACE("seed " + std::to_string(seed) + " map " + std::to_string(map) + " query " + std::to_string(q));
      const auto shape = r.shape(q);
      const auto tf = r.pose();
      found += expectSameAsFcl(octree, octree, *shape, tf, r.in(0.0, 0.4), nullptr);
      if (::testing::Test::HasFailure()) return;
    }
  }
  EXPECT_GT(found, queries / 10);  // queries near the maps
}

TEST(OctreeShapeDistance, AShapeTouchingAVoxelIsAtDistanceAboutZeroAndNeverAborts) {
  // Boxes, cylinders (on an end face) and spheres put against an occupied voxel's face, within
  // +-1 um of touching, some turned a little: a signed query answers within 1 mm of 0 (FCL's
  // own signed query asserts its collision query finds a contact; with GJK's tolerance it can
  // find a negative distance and no contact, and the process aborted).
  const unsigned seed = ehc_test::testSeed("OctreeShapeDistance touching");
  RandomQueries r(seed);
  fcl::DistanceRequest<double> req;
  req.enable_nearest_points = true;
  req.enable_signed_distance = true;
  for (int map = 0; map < 4; ++map) {
    // Voxels 1 m apart: a shape against one touches no other.
    const auto tree = std::make_shared<octomap::OcTree>(r.in(0.01, 0.05));
    for (int i = 0; i < 8; ++i) tree->updateNode(octomap::point3d(i + r.in(-0.1, 0.1), r.in(-0.1, 0.1), r.in(0.0, 0.5)), true);
    tree->updateInnerOccupancy();
    const fcl::OcTree<double> octree(std::static_pointer_cast<const octomap::OcTree>(tree));
    std::vector<Eigen::Vector3d> voxels;
    for (auto it = tree->begin_leafs(); it != tree->end_leafs(); ++it)
      if (tree->isNodeOccupied(*it)) voxels.emplace_back(it.getX(), it.getY(), it.getZ());
    ASSERT_EQ(voxels.size(), 8u);
    const double half = 0.5 * tree->getResolution();
    for (int q = 0; q < 300; ++q) {
      SCOPED_TRACE("seed " + std::to_string(seed) + " map " + std::to_string(map) + " query " + std::to_string(q));
      const Eigen::Vector3d c = voxels[static_cast<std::size_t>(r.in(0.0, 1.0) * (voxels.size() - 1))];
      const int axis = static_cast<int>(r.in(0.0, 2.999));
      const double sign = r.in(-1.0, 1.0) < 0.0 ? -1.0 : 1.0;
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      n[axis] = sign;
      const double gap = r.in(-1e-6, 1e-6), turn = q % 2 ? r.in(-0.02, 0.02) : 0.0;
      std::shared_ptr<fcl::CollisionGeometry<double>> g;
      double along = 0.0;  // the shape's half size along n
      switch (q % 3) {
        case 0: {
          const double h = r.in(0.01, 0.1);
          g = std::make_shared<fcl::Box<double>>(2 * h, 2 * h, 2 * h);
          along = h;
          break;
        }
        case 1: {
          const double len = r.in(0.02, 0.3);
          g = std::make_shared<fcl::Cylinder<double>>(r.in(0.01, 0.06), len);
          along = 0.5 * len;
          break;
        }
        default: along = r.in(0.01, 0.1); g = std::make_shared<fcl::Sphere<double>>(along); break;
      }
      g->computeLocalAABB();
      fcl::Transform3<double> tf = fcl::Transform3<double>::Identity();
      // The cylinder's axis (its z) along n, then turned a little about a perpendicular axis.
      tf.linear() = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), n).toRotationMatrix() *
                    Eigen::AngleAxisd(turn, Eigen::Vector3d::UnitX()).toRotationMatrix();
      tf.translation() = c + (half + along + gap) * n;
      fcl::DistanceResult<double> res;
      res.min_distance = 0.05;
      octreeShapeDistance(octree, *g, tf, req, &res);
      EXPECT_LT(std::abs(res.min_distance), 1e-3) << "voxel " << c.transpose() << " n " << n.transpose();
      if (::testing::Test::HasFailure()) return;
    }
  }
}

TEST(OctreeShapeDistance, ExclusionZonesGiveTheAnswerOnTheCopyWithoutThem) {
  const unsigned seed = ehc_test::testSeed("OctreeShapeDistance exclusion zones");
  RandomQueries r(seed);
  int found = 0, queries = 0;
  for (int map = 0; map < 8; ++map) {
    const std::shared_ptr<octomap::OcTree> tree = r.cloudMap();
    const fcl::OcTree<double> octree(std::static_pointer_cast<const octomap::OcTree>(tree));
    std::vector<ExclusionZone> zones(1 + map % 3);
    for (ExclusionZone& z : zones) z = {Eigen::Vector3d(r.in(-0.4, 0.4), r.in(-0.3, 0.3), r.in(0.0, 0.4)), r.in(0.01, 0.3)};
    const fcl::OcTree<double> copy(copyWithoutZones(*tree, zones));
    const OcTreeExclusion exclusion{*tree, zones, [&copy]() -> const fcl::OcTree<double>& { return copy; }};
    for (int q = 0; q < 60; ++q, ++queries) {
      SCOPED_TRACE("seed " + std::to_string(seed) + " map " + std::to_string(map) + " query " + std::to_string(q));
      const auto shape = r.shape(q);
      fcl::Transform3<double> tf = r.pose();
      if (q % 2) tf.translation() = zones[0].centre + Eigen::Vector3d(r.in(-0.2, 0.2), r.in(-0.2, 0.2), r.in(-0.2, 0.2));
      found += expectSameAsFcl(octree, copy, *shape, tf, r.in(0.0, 0.4), &exclusion);
      if (::testing::Test::HasFailure()) return;
    }
  }
  EXPECT_GT(found, queries / 10);
}
