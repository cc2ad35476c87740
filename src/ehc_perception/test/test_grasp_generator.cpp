// GraspGenerator: synthetic box / cylinder / lying bottle clouds with noise, scenes with a
// table, depth refinement (standing box, short box on a table), bad clouds and bad configs.
#include "ehc_common/config_node.h"
#include "ehc_perception/grasp_generator.h"
#include "ehc_test/perception_fixtures.h"
#include "ehc_test/test_seed.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <utility>

using ehc_common::ConfigNode;

using namespace ehc_perception;
using namespace ehc_perception::test;

namespace {

constexpr double kDeg = M_PI / 180.0;
const Eigen::Vector3d kView(0.0, 0.0, 0.9);  // camera above and behind the objects

/// Distance from the grasp centre to `centre` measured in the plane perpendicular to the
/// approach axis (the centroid's projection onto the grasp plane).
double lateralOffset(const Grasp& g, const Eigen::Vector3d& centre) {
  const Eigen::Vector3d d = centre - g.pose.translation();
  const Eigen::Vector3d a = g.pose.linear().col(2);
  return (d - d.dot(a) * a).norm();
}

double angleToAxis(const Eigen::Vector3d& v, const Eigen::Vector3d& axis) {
  return std::acos(std::min(1.0, std::abs(v.normalized().dot(axis.normalized()))));
}

void expectValidFrame(const Grasp& g) {
  const Eigen::Matrix3d R = g.pose.linear();
  EXPECT_NEAR((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-9);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-9);
  EXPECT_GT(g.score, 0.0);
  EXPECT_LE(g.score, 1.0);
}

void expectAboveTable(const Grasp& g, double table_z) {
  // Grasp centre above the table, approach not from below.
  EXPECT_GT(g.pose.translation().z(), table_z);
  EXPECT_LT(g.pose.linear().col(2).z(), 0.1);
}

}  // namespace

TEST(GraspGenerator, StandingBoxWithNoise) {
  const Eigen::Isometry3d T = pose(0.6, 0.1, 0.05, 30 * kDeg);
  Surface s = boxSurface(Eigen::Vector3d(0.05, 0.12, 0.10), 0.003);
  s.transform(T);
  const GraspGenerator gen{GraspGeneratorConfig()};
  const GraspResult r = gen.generate(s.noisy(0.0015, 1), kView);
  ASSERT_FALSE(r.grasps.empty()) << r.reason;
  EXPECT_TRUE(r.reason.empty());
  const Grasp& best = r.grasps.front();
  expectValidFrame(best);
  expectAboveTable(best, 0.0);
  EXPECT_LE(lateralOffset(best, T.translation()), 0.01);
  // Fingers close across the 5 cm side (box x axis).
  EXPECT_LE(angleToAxis(best.pose.linear().col(1), T.linear().col(0)), 10 * kDeg);
  EXPECT_LT(best.width, 0.07);
  EXPECT_GT(best.width, 0.045);
  for (std::size_t i = 1; i < r.grasps.size(); ++i)
    EXPECT_GE(r.grasps[i - 1].score, r.grasps[i].score);
}

TEST(GraspGenerator, StandingBoxSeenFromOneViewpoint) {
  const Eigen::Isometry3d T = pose(0.7, -0.1, 0.05, -20 * kDeg);
  Surface s = boxSurface(Eigen::Vector3d(0.05, 0.12, 0.10), 0.003);
  s.transform(T);
  const Surface visible = s.visibleFrom(kView);
  ASSERT_LT(visible.points.size(), s.points.size());
  const GraspGenerator gen{GraspGeneratorConfig()};
  const GraspResult r = gen.generate(visible.noisy(0.0015, 2), kView);
  ASSERT_FALSE(r.grasps.empty()) << r.reason;
  const Grasp& best = r.grasps.front();
  expectAboveTable(best, 0.0);
  // One view: the centre of gravity the generator sees is the visible cloud's centroid
  // (biased towards the camera). The grasp is moved onto it along the finger breadth axis
  // (x) and centred between the object's sides along the closing axis (y).
  const Eigen::Matrix3d R = best.pose.linear();
  EXPECT_LE(std::abs(R.col(0).dot(visible.centroid() - best.pose.translation())), 0.01);
  EXPECT_LE(std::abs(R.col(1).dot(T.translation() - best.pose.translation())), 0.01);
  EXPECT_LE(lateralOffset(best, T.translation()), 0.03);
  EXPECT_LE(angleToAxis(R.col(1), T.linear().col(0)), 10 * kDeg);
  EXPECT_LT(best.width, 0.07);
  EXPECT_GT(best.width, 0.045);
}

// Random boxes seen from random viewpoints (any azimuth, 20-60 deg up): every grasp approaches
// from the side the view shows (within max_approach_tilt_deg of the view direction), and a box
// narrower than the opening keeps a grasp.
TEST(GraspGenerator, ApproachesComeFromTheSideTheViewShows) {
  std::mt19937 rng(ehc_test::testSeed("GraspGenerator.ApproachesComeFromTheSideTheViewShows"));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const GraspGeneratorConfig cfg;
  const GraspGenerator gen(cfg);
  for (int i = 0; i < 6; ++i) {
    const Eigen::Vector3d size(0.03 + 0.03 * unit(rng), 0.03 + 0.09 * unit(rng), 0.04 + 0.08 * unit(rng));
    const Eigen::Isometry3d T = pose(0.6, 0.0, 0.5 * size.z(), 2.0 * M_PI * unit(rng));
    Surface s = boxSurface(size, 0.003);
    s.transform(T);
    const double az = 2.0 * M_PI * unit(rng), el = (20.0 + 40.0 * unit(rng)) * kDeg, d = 0.5 + 0.2 * unit(rng);
    const Eigen::Vector3d eye =
        T.translation() + d * Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    const Surface visible = s.visibleFrom(eye);
    const GraspResult r = gen.generate(visible.noisy(0.0015, static_cast<unsigned>(i + 1)), eye);
    SCOPED_TRACE("box " + std::to_string(i) + ", azimuth " + std::to_string(az / kDeg) + " deg, elevation " +
                 std::to_string(el / kDeg) + " deg");
    ASSERT_FALSE(r.grasps.empty()) << r.reason;
    const Eigen::Vector3d view = (r.centroids.front() - eye).normalized();
    for (const Grasp& g : r.grasps)
      EXPECT_GE(g.pose.linear().col(2).dot(view), std::cos(cfg.max_approach_tilt_deg * kDeg) - 1e-9);
  }
}

TEST(GraspGenerator, StandingCylinderWithNoise) {
  const Eigen::Isometry3d T = pose(0.5, -0.2, 0.0, 0.0);
  Surface s = cylinderSurface(0.03, 0.0, 0.12, 0.003, false, true);
  s.transform(T);
  const GraspGenerator gen{GraspGeneratorConfig()};
  const GraspResult r = gen.generate(s.noisy(0.0015, 3), kView);
  ASSERT_FALSE(r.grasps.empty()) << r.reason;
  const Grasp& best = r.grasps.front();
  expectValidFrame(best);
  expectAboveTable(best, 0.0);
  EXPECT_LE(lateralOffset(best, Eigen::Vector3d(0.5, -0.2, 0.06)), 0.01);
  // Fingers close across the diameter: perpendicular to the cylinder axis.
  EXPECT_GE(angleToAxis(best.pose.linear().col(1), Eigen::Vector3d::UnitZ()), 80 * kDeg);
  EXPECT_LT(best.width, 0.07);
  EXPECT_GT(best.width, 0.055);
}

TEST(GraspGenerator, LyingBottleWithNoise) {
  // Bottle lying on the table, axis horizontal at yaw 20 deg.
  Surface s = bottleSurface(0.03, 0.14, 0.03, 0.013, 0.05, 0.003);
  const Eigen::Isometry3d T = pose(0.55, 0.05, 0.03, 20 * kDeg, 90 * kDeg);  // local z -> world
  s.transform(T);
  const Eigen::Vector3d axis = T.linear().col(2);
  ASSERT_NEAR(axis.z(), 0.0, 1e-9);
  const Eigen::Vector3d centroid = s.centroid();
  const GraspGenerator gen{GraspGeneratorConfig()};
  const GraspResult r = gen.generate(s.noisy(0.0015, 4), kView);
  ASSERT_FALSE(r.grasps.empty()) << r.reason;
  const Grasp& best = r.grasps.front();
  expectValidFrame(best);
  expectAboveTable(best, 0.0);
  EXPECT_LE(lateralOffset(best, centroid), 0.01)
      << "grasp at " << best.pose.translation().transpose() << ", centroid "
      << centroid.transpose();
  EXPECT_GE(angleToAxis(best.pose.linear().col(1), axis), 80 * kDeg);
  EXPECT_LT(best.width, 0.07);
}

TEST(GraspGenerator, TooWideObjectHasNoGraspAndAReason) {
  Surface s = boxSurface(Eigen::Vector3d(0.20, 0.20, 0.15), 0.004);
  s.transform(pose(0.6, 0.0, 0.075, 0.0));
  const GraspGenerator gen{GraspGeneratorConfig()};
  const GraspResult r = gen.generate(s.noisy(0.001, 5), kView);
  EXPECT_TRUE(r.grasps.empty());
  EXPECT_FALSE(r.reason.empty());
}

TEST(GraspGenerator, BadCloudsGiveNoGraspAndAClearReason) {
  const GraspGenerator gen{GraspGeneratorConfig()};
  GraspResult r = gen.generate({}, kView);
  EXPECT_TRUE(r.grasps.empty());
  EXPECT_EQ(r.reason, "empty cloud");

  const float nan = std::numeric_limits<float>::quiet_NaN();
  PointList all_nan(500, Eigen::Vector3f(nan, 0.f, 1.f));
  all_nan.push_back(Eigen::Vector3f(std::numeric_limits<float>::infinity(), 0.f, 0.f));
  r = gen.generate(all_nan, kView);
  EXPECT_TRUE(r.grasps.empty());
  EXPECT_NE(r.reason.find("NaN"), std::string::npos) << r.reason;

  r = gen.generate({Eigen::Vector3f(0.5f, 0.f, 0.05f)}, kView);
  EXPECT_TRUE(r.grasps.empty());
  EXPECT_NE(r.reason.find("only 1 points"), std::string::npos) << r.reason;

  Surface s = cylinderSurface(0.03, 0.0, 0.12, 0.003, false, true);
  r = gen.generate(s.points, Eigen::Vector3d(std::nan(""), 0, 0));
  EXPECT_TRUE(r.grasps.empty());
  EXPECT_NE(r.reason.find("viewpoint"), std::string::npos);

  // NaN points mixed into a good cloud are skipped, not fatal.
  PointList mixed = s.points;
  mixed.insert(mixed.end(), all_nan.begin(), all_nan.end());
  r = gen.generate(mixed, kView);
  EXPECT_FALSE(r.grasps.empty()) << r.reason;
  EXPECT_EQ(r.finite_points, static_cast<int>(s.points.size()));

  // Scene entry point with the same inputs.
  EXPECT_FALSE(gen.generateFromScene({}, kView).reason.empty());
  EXPECT_FALSE(gen.generateFromScene(all_nan, kView).reason.empty());
}

// A view over a table's edge that shows more floor than table top (random table height, object
// place and yaw; seed printed): with the target's place given, the support is the table under
// it, not the larger floor, so the table's edge is no object; the target is found on the table;
// a place with no plane within max_object_extent under it has no object at all.
TEST(GraspGenerator, TheSupportIsThePlaneUnderTheTargetNotTheLargestOne) {
  std::mt19937 rng(ehc_test::testSeed("GraspGenerator.TheSupportIsThePlaneUnderTheTarget"));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const GraspGenerator gen{GraspGeneratorConfig()};
  for (int trial = 0; trial < 5; ++trial) {
    const double table_z = 0.6 + 0.2 * unit(rng);
    Surface scene = tableSurface(0.9, 0.0, 1.0, 1.0, 0.0, 0.01);  // floor: the larger plane
    scene.append(tableSurface(1.1, 0.0, 0.6, 0.6, table_z, 0.01));
    Surface edge = boxSurface(Eigen::Vector3d(0.005, 0.6, 0.04), 0.005);  // the top's front face
    edge.transform(pose(0.8, 0.0, table_z - 0.02, 0.0));
    scene.append(edge);
    const Eigen::Vector3d place(0.95 + 0.2 * unit(rng), -0.2 + 0.4 * unit(rng), table_z + 0.04);
    Surface box = boxSurface(Eigen::Vector3d(0.05, 0.05, 0.08), 0.004);
    box.transform(pose(place.x(), place.y(), place.z(), 2.0 * M_PI * unit(rng)));
    scene.append(box);
    const PointList cloud = scene.noisy(0.001, static_cast<unsigned>(trial));
    const Eigen::Vector3d view(0.3, 0.0, table_z + 0.5);
    SCOPED_TRACE("table at " + std::to_string(table_z) + " m, object at " + std::to_string(place.x()) + ", " +
                 std::to_string(place.y()));

    const SceneSegmentation largest = gen.segmentScene(cloud, &view);
    ASSERT_TRUE(largest.plane_found);
    EXPECT_NEAR(-largest.plane[3], 0.0, 0.01) << "the floor is the larger plane of this view";

    const SceneSegmentation seg = gen.segmentScene(cloud, &view, &place);
    ASSERT_TRUE(seg.plane_found) << seg.reason;
    // The object's place is 4 cm above the table (the plane's height taken there: a plane fitted
    // within plane_distance may tilt a little).
    EXPECT_NEAR(seg.plane.head<3>().dot(place) + seg.plane[3], place.z() - table_z, gen.config().plane_distance);
    ASSERT_FALSE(seg.objects.empty()) << seg.reason;
    for (const PointList& o : seg.objects)
      for (const auto& p : o) EXPECT_GT(p.z(), table_z) << "a point of the table's edge is an object";
    const Eigen::Vector3d above_edge(0.82, 0.0, table_z + 0.03);
    for (const PointList& o : gen.segmentScene(cloud, &view, &above_edge).objects)
      for (const auto& p : o) EXPECT_GT(p.z(), table_z);

    const Eigen::Vector3d in_the_air(place.x(), place.y(), table_z + 1.0);
    const SceneSegmentation none = gen.segmentScene(cloud, &view, &in_the_air);
    EXPECT_TRUE(none.objects.empty());
    EXPECT_NE(none.reason.find("no support plane under the target"), std::string::npos) << none.reason;
  }
}

namespace {
/// A table top at `table_z` with a 5 x 12 x 10 cm box standing at (0.65, 0.15) and a cylinder
/// (r 3 cm, 12 cm tall) at (0.75, -0.15).
Surface boxAndCylinderOnATable(double table_z) {
  Surface scene = tableSurface(0.7, 0.0, 0.6, 0.8, table_z, 0.005);
  Surface box = boxSurface(Eigen::Vector3d(0.05, 0.12, 0.10), 0.003);
  box.transform(pose(0.65, 0.15, table_z + 0.05, 0.4));
  Surface cyl = cylinderSurface(0.03, 0.0, 0.12, 0.003, false, true);
  cyl.transform(pose(0.75, -0.15, table_z, 0.0));
  scene.append(box);
  scene.append(cyl);
  return scene;
}
}  // namespace

TEST(GraspGenerator, SceneWithTableIsSegmentedAndGraspsAvoidTheTable) {
  const double table_z = 0.70;
  Surface scene = boxAndCylinderOnATable(table_z);
  const PointList cloud = scene.noisy(0.001, 6);
  const Eigen::Vector3d view(0.2, 0.0, 1.3);
  const GraspGenerator gen{GraspGeneratorConfig()};

  const SceneSegmentation seg = gen.segmentScene(cloud);
  ASSERT_TRUE(seg.plane_found) << seg.reason;
  EXPECT_NEAR(std::abs(seg.plane[2]), 1.0, 0.01);
  EXPECT_NEAR(-seg.plane[3] / seg.plane[2], table_z, 0.005);
  ASSERT_EQ(seg.objects.size(), 2u);

  const Eigen::Vector3d near_cyl(0.75, -0.15, table_z + 0.06);
  const GraspResult r = gen.generateFromScene(cloud, view, &near_cyl);
  ASSERT_FALSE(r.grasps.empty()) << r.reason;
  EXPECT_TRUE(r.support_plane_found);
  for (const Grasp& g : r.grasps) {
    EXPECT_LT((g.pose.translation() - near_cyl).head<2>().norm(), 0.05);
    expectAboveTable(g, table_z);
  }
  EXPECT_GE(angleToAxis(r.grasps.front().pose.linear().col(1), Eigen::Vector3d::UnitZ()),
            80 * kDeg);

  const GraspResult all = gen.generateFromScene(cloud, view);
  EXPECT_EQ(all.objects, 2);
  bool has0 = false, has1 = false;
  for (const Grasp& g : all.grasps) (g.object == 0 ? has0 : has1) = true;
  EXPECT_TRUE(has0 && has1);
}

TEST(GraspGenerator, ACloudTargetsGraspsComeFromTheClusterItWasFoundIn) {
  const double table_z = 0.70;
  Surface scene = boxAndCylinderOnATable(table_z);
  const Eigen::Isometry3d camera = lookAt(Eigen::Vector3d(0.2, 0.0, 1.3), Eigen::Vector3d(0.7, 0.0, table_z));
  const PointList cloud = scene.visibleFrom(camera.translation()).noisy(0.001, 6);
  const GraspGenerator gen{GraspGeneratorConfig()};
  const GraspTargetingParams targeting;
  ehc_control::TargetSelector nearest;
  nearest.kind = ehc_control::TargetSelectorKind::Nearest;
  ehc_control::TargetSelector left;
  left.kind = ehc_control::TargetSelectorKind::KthFromLeft;
  const Eigen::Vector3d cyl_at(0.75, -0.15, table_z + 0.06), box_at(0.65, 0.15, table_z + 0.05);
  nearest.point = cyl_at;
  struct Case {
    const ehc_control::TargetSelector* selector;
    const Eigen::Vector3d* tracked;
    Eigen::Vector3d truth;
  };
  for (const Case& c : {Case{&nearest, nullptr, cyl_at}, Case{&left, nullptr, box_at}, Case{&left, &cyl_at, cyl_at}}) {
    const CloudTargetResult r = generateForCloudTarget(gen, cloud, camera, *c.selector, c.tracked, targeting);
    ASSERT_TRUE(r.selection.selected()) << r.selection.detail;
    EXPECT_LT((r.selection.centre - c.truth).head<2>().norm(), 0.04) << r.selection.detail;
    ASSERT_GE(r.object, 0);
    ASSERT_LT(static_cast<std::size_t>(r.object), r.segmentation.objects.size());
    EXPECT_EQ(r.segmentation.objects.size(), 2u);
    EXPECT_TRUE(r.segmentation.plane_found);
    // The centre is its cluster's centroid, and every grasp is on that cluster.
    EXPECT_LT((r.segmentation.centroid(static_cast<std::size_t>(r.object)) - r.selection.centre).norm(), 1e-6);
    ASSERT_FALSE(r.grasps.grasps.empty()) << r.grasps.reason;
    for (const Grasp& g : r.grasps.grasps) EXPECT_EQ(g.object, r.object);
  }
  // Tracked where nothing is: no target, and no grasps from elsewhere.
  const Eigen::Vector3d nowhere(0.70, 0.0, table_z + 0.5);
  const CloudTargetResult gone = generateForCloudTarget(gen, cloud, camera, left, &nowhere, targeting);
  EXPECT_FALSE(gone.selection.selected());
  EXPECT_NE(gone.selection.detail.find("not in the view"), std::string::npos) << gone.selection.detail;
  EXPECT_TRUE(gone.grasps.grasps.empty());
  // A non-finite tracked pose is no pose: the selector chooses.
  const Eigen::Vector3d nan(std::nan(""), 0.0, 0.0);
  const CloudTargetResult chosen = generateForCloudTarget(gen, cloud, camera, nearest, &nan, targeting);
  ASSERT_TRUE(chosen.selection.selected()) << chosen.selection.detail;
  EXPECT_LT((chosen.selection.centre - cyl_at).head<2>().norm(), 0.04);
}

TEST(GraspGenerator, IsDeterministic) {
  Surface s = cylinderSurface(0.03, 0.0, 0.12, 0.003, false, true);
  const PointList cloud = s.noisy(0.0015, 7);
  const GraspGenerator gen{GraspGeneratorConfig()};
  const GraspResult a = gen.generate(cloud, kView), b = gen.generate(cloud, kView);
  ASSERT_EQ(a.grasps.size(), b.grasps.size());
  for (std::size_t i = 0; i < a.grasps.size(); ++i)
    EXPECT_TRUE(a.grasps[i].pose.isApprox(b.grasps[i].pose));
}

TEST(GraspGenerator, ConfigLoadsAndBadValuesFailNamingTheField) {
  const auto ok = ConfigNode::loadString(
      "grasp_generator: {top_k: 3, voxel_size: 0.005, gripper: {max_width: 0.08}}", "ok.yaml",
      "GraspGenerator");
  const GraspGeneratorConfig c = loadGraspGeneratorConfig(ok.child("grasp_generator"));
  EXPECT_EQ(c.top_k, 3);
  EXPECT_DOUBLE_EQ(c.gripper.max_width, 0.08);
  const auto depth = ConfigNode::loadString(
      "grasp_generator: {max_depth_shift: 0.03, depth_step: 0.0025, depth_margin: 0.004}",
      "ok.yaml", "GraspGenerator");
  const GraspGeneratorConfig cd = loadGraspGeneratorConfig(depth.child("grasp_generator"));
  EXPECT_DOUBLE_EQ(cd.max_depth_shift, 0.03);
  EXPECT_DOUBLE_EQ(cd.depth_step, 0.0025);
  EXPECT_DOUBLE_EQ(cd.depth_margin, 0.004);
  EXPECT_NE(cd.summary().find("depth shift <= 0.03 m"), std::string::npos) << cd.summary();

  auto expectFails = [](const std::string& yaml, const std::string& needle) {
    const auto n = ConfigNode::loadString(yaml, "bad.yaml", "GraspGenerator");
    try {
      loadGraspGeneratorConfig(n.childOrEmpty("grasp_generator"));
      ADD_FAILURE() << "no error for " << yaml;
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("[GraspGenerator]"), std::string::npos) << what;
      EXPECT_NE(what.find(needle), std::string::npos) << what;
      EXPECT_NE(what.find("bad.yaml"), std::string::npos) << what;
    }
  };
  expectFails("grasp_generator: {voxel_size: -0.01}", "voxel_size");
  expectFails("grasp_generator: {gripper: {max_width: 0}}", "gripper.max_width");
  expectFails("grasp_generator: {top_k: many}", "top_k");
  expectFails("grasp_generator: {up: [0, 0]}", "up");
  expectFails("grasp_generator: {up: [0, 0, 0]}", "up");
  expectFails("grasp_generator: {friction_coefficient: .nan}", "friction_coefficient");
  // Depth refinement.
  expectFails("grasp_generator: {max_depth_shift: -0.01}", "'max_depth_shift'");
  expectFails("grasp_generator: {max_depth_shift: 0.9}", "'max_depth_shift'");
  expectFails("grasp_generator: {depth_step: 0}", "'depth_step'");           // enabled: > 0
  expectFails("grasp_generator: {depth_step: -0.001}", "'depth_step'");
  expectFails("grasp_generator: {max_depth_shift: 0.02, depth_step: 0.03}", "'depth_step'");
  expectFails("grasp_generator: {depth_step: 0.00001}", "'depth_step'");     // > 1000 steps
  expectFails("grasp_generator: {depth_margin: -0.001}", "'depth_margin'");
  expectFails("grasp_generator: {max_depth_shift: 0.01, depth_margin: 0.01}", "'depth_margin'");
  expectFails("grasp_generator: {depth_margin: .inf}", "depth_margin");
  // Disabled (max_depth_shift 0): step and margin are not constrained by it.
  const auto off = ConfigNode::loadString(
      "grasp_generator: {max_depth_shift: 0, depth_step: 0, depth_margin: 0.01}", "off.yaml",
      "GraspGenerator");
  const GraspGeneratorConfig c_off = loadGraspGeneratorConfig(off.child("grasp_generator"));
  EXPECT_EQ(c_off.max_depth_shift, 0.0);
}

namespace {

/// Best grasp whose approach is within `max_tilt` of straight down (nullptr if none).
const Grasp* bestTopDown(const GraspResult& r, double max_tilt) {
  for (const Grasp& g : r.grasps)  // best first
    if (std::acos(std::min(1.0, -g.pose.linear().col(2).z())) <= max_tilt) return &g;
  return nullptr;
}

Eigen::Vector3d fingertips(const Grasp& g, const GripperGeometry& gr) {
  return g.pose * Eigen::Vector3d(0, 0, gr.finger_tip_depth);
}

/// Centre of the palm's front face (where the fingers start).
Eigen::Vector3d palmFace(const Grasp& g, const GripperGeometry& gr) {
  return g.pose * Eigen::Vector3d(0, 0, gr.finger_tip_depth - gr.finger_length);
}

/// Lowest corner of the finger boxes' tips above the plane z = table_z.
double lowestFingertipHeight(const Grasp& g, const GripperGeometry& gr, double table_z) {
  double lowest = std::numeric_limits<double>::max();
  for (double sx : {-1.0, 1.0})
    for (double sy : {-1.0, 1.0}) {
      const Eigen::Vector3d corner =
          g.pose * Eigen::Vector3d(sx * 0.5 * gr.finger_breadth,
                                   sy * (0.5 * g.width + gr.finger_thickness),
                                   gr.finger_tip_depth);
      lowest = std::min(lowest, corner.z() - table_z);
    }
  return lowest;
}

/// A box of `size` standing at `at` (x, y) on a table at `table_z` (yaw `yaw`), the scene
/// seen from `view` (visible points only) with 1 mm noise.
PointList boxOnTable(const Eigen::Vector3d& size, const Eigen::Vector2d& at, double yaw,
                     double table_z, const Eigen::Vector3d& view, unsigned seed) {
  Surface scene = tableSurface(at.x(), at.y(), 0.5, 0.6, table_z, 0.005);
  Surface box = boxSurface(size, 0.003);
  box.transform(pose(at.x(), at.y(), table_z + 0.5 * size.z(), yaw));
  scene.append(box);
  return scene.visibleFrom(view).noisy(0.001, seed);
}

}  // namespace

TEST(GraspGenerator, DepthRefinementPutsTheFingersDeepOnAStandingBox) {
  // 6 x 6 x 12 cm box standing on a table, one view from above and in front, at several
  // yaws. The contact pairs alone often leave the top-down grasp near the top edge (fingers
  // overlapping the box by ~2 cm); the depth refinement pushes it down until the palm nears
  // the top.
  const double table_z = 0.70, top = table_z + 0.12;
  const Eigen::Vector2d at(0.6, 0.02);
  const Eigen::Vector3d view(0.1, 0.0, 1.3);
  const Eigen::Vector3d near(at.x(), at.y(), table_z + 0.06);
  GraspGeneratorConfig cfg;
  const GripperGeometry gr = cfg.gripper;
  GraspGeneratorConfig cfg0 = cfg;
  cfg0.max_depth_shift = 0.0;  // refinement off: the grasps as before this step existed
  const GraspGenerator gen(cfg), gen0(cfg0);
  double sum = 0, sum0 = 0;
  int n = 0;
  for (int yaw = 15; yaw <= 75; yaw += 15) {
    SCOPED_TRACE("yaw " + std::to_string(yaw));
    const PointList cloud =
        boxOnTable(Eigen::Vector3d(0.06, 0.06, 0.12), at, yaw * kDeg, table_z, view, 1);
    const GraspResult deep = gen.generateFromScene(cloud, view, &near);
    const GraspResult shallow = gen0.generateFromScene(cloud, view, &near);
    const Grasp* g = bestTopDown(deep, 20 * kDeg);
    const Grasp* g0 = bestTopDown(shallow, 20 * kDeg);
    ASSERT_TRUE(g) << deep.reason;
    ASSERT_TRUE(g0) << shallow.reason;
    expectValidFrame(*g);
    // Fingertips well inside the box's height, palm not into its top.
    const double tip = top - fingertips(*g, gr).z(), tip0 = top - fingertips(*g0, gr).z();
    const double palm = palmFace(*g, gr).z() - top;
    EXPECT_GE(tip, 0.03);
    EXPECT_GT(palm, 0.0);
    // Never shallower than without the refinement.
    EXPECT_GE(tip, tip0 - 1e-9);
    std::printf("standing 6x6x12 cm box, yaw %2d deg, best top-down grasp: fingertips %.1f mm "
                "below the top (%.1f mm without depth refinement), palm %.1f mm above it\n",
                yaw, 1e3 * tip, 1e3 * tip0, 1e3 * palm);
    sum += tip;
    sum0 += tip0;
    ++n;
  }
  // Without the refinement the grasps are no deeper (the best unrefined grasp can already be deep).
  EXPECT_GE(sum, sum0 - 1e-9);
  RecordProperty("mean_fingertips_below_top_mm", std::to_string(1e3 * sum / n));
  RecordProperty("mean_fingertips_below_top_unrefined_mm", std::to_string(1e3 * sum0 / n));
}

TEST(GraspGenerator, DepthRefinementStopsAboveTheSupport) {
  // A 4 cm tall box: the push is limited by the table (fingertips must stay
  // support_clearance above it), not by the palm or max_depth_shift.
  const double table_z = 0.70;
  const Eigen::Vector2d at(0.6, 0.02);
  const Eigen::Vector3d view(0.1, 0.0, 1.3);
  const PointList cloud =
      boxOnTable(Eigen::Vector3d(0.05, 0.05, 0.04), at, 30 * kDeg, table_z, view, 1);
  const Eigen::Vector3d near(at.x(), at.y(), table_z + 0.02);

  GraspGeneratorConfig cfg;
  const GripperGeometry gr = cfg.gripper;
  const GraspResult deep = GraspGenerator(cfg).generateFromScene(cloud, view, &near);
  ASSERT_FALSE(deep.grasps.empty()) << deep.reason;
  ASSERT_TRUE(deep.support_plane_found);
  // Tolerance: the support plane is estimated from the noisy table (RANSAC).
  for (const Grasp& g : deep.grasps) {
    expectValidFrame(g);
    EXPECT_GE(lowestFingertipHeight(g, gr, table_z), cfg.support_clearance - 0.0015)
        << "grasp at " << g.pose.translation().transpose();
  }
  // The refinement did push the top-down grasp down (towards the table).
  cfg.max_depth_shift = 0.0;
  const GraspResult shallow = GraspGenerator(cfg).generateFromScene(cloud, view, &near);
  const Grasp* g = bestTopDown(deep, 20 * kDeg);
  const Grasp* g0 = bestTopDown(shallow, 20 * kDeg);
  ASSERT_TRUE(g && g0);
  EXPECT_LT(fingertips(*g, gr).z(), fingertips(*g0, gr).z());
}

TEST(PointCloudIO, RoundTripAndBadFiles) {
  Surface s = cylinderSurface(0.03, 0.0, 0.12, 0.01, false, true);
  const std::string path = "/tmp/ehc_perception_test_cloud.pcd";
  savePcd(path, s.points);
  const PointList back = loadPcd(path);
  ASSERT_EQ(back.size(), s.points.size());
  EXPECT_TRUE(back[5].isApprox(s.points[5]));
  savePcd(path, {});
  EXPECT_TRUE(loadPcd(path).empty());
  EXPECT_THROW(loadPcd("/nonexistent/cloud.pcd"), std::invalid_argument);
  std::ofstream("/tmp/ehc_perception_garbage.pcd") << "this is not a point cloud\n";
  try {
    loadPcd("/tmp/ehc_perception_garbage.pcd");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("[PointCloudIO]"), std::string::npos);
  }
}

// ---------------------------------------------------------------- work per cloud

namespace {

/// A table (0.8 x 1.2 m top at 0.7 m) with a box on it, seen by a depth camera 0.4-0.8 m from
/// the box, 35-65 deg above it: a random scene of `rng`.
struct TableScene {
  Box table, object;
  Eigen::Isometry3d camera;
};
TableScene randomTableScene(std::mt19937* rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  TableScene s;
  s.table.pose = pose(1.0, 0.0, 0.685, 0.0);
  s.table.size = Eigen::Vector3d(0.8, 1.2, 0.03);
  const double w = 0.03 + 0.03 * u(*rng), h = 0.06 + 0.08 * u(*rng);
  s.object.size = Eigen::Vector3d(w, 0.04 + 0.04 * u(*rng), h);
  s.object.pose = pose(0.9 + 0.1 * u(*rng), -0.2 + 0.4 * u(*rng), 0.7 + 0.5 * h, M_PI * u(*rng));
  const double dist = 0.4 + 0.4 * u(*rng), el = (35.0 + 30.0 * u(*rng)) * kDeg, az = (-30.0 + 60.0 * u(*rng)) * kDeg;
  const Eigen::Vector3d c = s.object.pose.translation();
  s.camera = lookAt(c + dist * Eigen::Vector3d(-std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)), c);
  return s;
}

}  // namespace

TEST(GraspBudget, TheWorkPerCloudIsBoundedWhateverTheCloud) {
  const GraspGenerator gen{GraspGeneratorConfig()};
  const GraspTargetingParams targeting;
  const int budget = targeting.max_input_points, per_object = gen.config().max_object_points;
  const unsigned seed = 7;
  std::printf("seed %u\n", seed);
  std::mt19937 rng(seed);
  // 2 M points: a dense 0.2 m blob (one cluster of every point), points spread over 3 km (the
  // voxel grid's indices would overflow: PCL's VoxelGrid then filters nothing), all at the origin.
  std::uniform_real_distribution<float> blob(0.0f, 0.2f), far(-1500.0f, 1500.0f);
  PointList dense, spread, zeros(2000000, Eigen::Vector3f::Zero());
  for (int i = 0; i < 2000000; ++i) {
    dense.emplace_back(1.0f + blob(rng), blob(rng), 0.7f + blob(rng));
    spread.emplace_back(far(rng), far(rng), far(rng));
  }
  const Eigen::Vector3d target(1.1, 0.1, 0.8);
  for (const PointList* cloud : {&dense, &spread, &zeros}) {
    for (const Eigen::Vector3d* t : {&target, static_cast<const Eigen::Vector3d*>(nullptr)}) {
      const GraspResult r = generateForTarget(gen, *cloud, kView, t, targeting);
      EXPECT_EQ(r.input_points, 2000000);
      EXPECT_EQ(r.budget_points, budget);
      EXPECT_LE(r.filtered_points, per_object * std::max(1, r.objects)) << r.reason;
      EXPECT_LE(r.finite_points, budget);
    }
  }
  // The dense blob is one object over max_object_points: voxelised coarser, to the bound.
  const GraspResult r = generateForTarget(gen, dense, kView, &target, targeting);
  ASSERT_EQ(r.objects, 1) << r.reason;
  EXPECT_LE(r.filtered_points, per_object);
  EXPECT_GT(r.voxel_size, gen.config().voxel_size);
  // Spread over 3 km: an object there is bounded by the stride when the grid cannot.
  GraspGeneratorConfig few;
  few.max_object_points = 100;
  PointList wide;
  for (int i = 0; i < 400; ++i) wide.emplace_back(1500.0f * (i % 2 ? 1 : -1), 0.001f * i, 0.0f);
  EXPECT_LE(GraspGenerator(few).generate(wide, kView).filtered_points, 100);
}

/// The cluster of `seg` nearest `centre`: its centroid and its extent along the box's axes.
struct Cluster {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero(), lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();
};
Cluster nearestCluster(const SceneSegmentation& seg, const Box& box) {
  Cluster c;
  const int o = seg.nearestObject(box.pose.translation());
  if (o < 0) return c;
  c.centroid = seg.centroid(static_cast<std::size_t>(o));
  c.lo.setConstant(1e9);
  c.hi.setConstant(-1e9);
  for (const auto& p : seg.objects[static_cast<std::size_t>(o)]) {
    const Eigen::Vector3d q = box.pose.inverse() * p.cast<double>();
    c.lo = c.lo.cwiseMin(q);
    c.hi = c.hi.cwiseMax(q);
  }
  return c;
}

TEST(GraspBudget, AFullResolutionFrameReadWithinTheBudgetKeepsItsGeometry) {
  // Organised 640x480 depth frames of a box on a table (random box, pose and view), read whole
  // and within the point budget (every 4th row and column, PointBudget): the same support plane
  // (within 2 deg, 5 mm), the box's cluster with the same extent along the box's axes (within
  // 1 cm: the budget's spacing at these distances is 4-8 mm; measured: within 6 mm) and centroid
  // (within 2 cm; measured 0.3-1.7 cm: the whole frame fills every 4 mm voxel of the faces seen
  // at a grazing angle, the budget's points weigh the faces by their area in the image), and
  // grasps from both or from neither.
  const GraspGenerator gen{GraspGeneratorConfig()};
  GraspTargetingParams whole, budgeted;
  whole.max_input_points = 10000000;
  const unsigned seed = 11;
  std::printf("seed %u\n", seed);
  std::mt19937 rng(seed);
  for (int k = 0; k < 8; ++k) {
    const TableScene s = randomTableScene(&rng);
    const PointList frame = depthCameraCloud(640, 480, s.camera, {s.table, s.object}, 0.001, seed + k);
    const PackedCloud msg = packCloud(frame, xyzFloat32(), 480);
    const CloudPoints all = msg.extract(), read = msg.extract(static_cast<std::size_t>(budgeted.max_input_points));
    ASSERT_EQ(read.read, 19200u);
    SCOPED_TRACE("scene " + std::to_string(k) + ": box " + std::to_string(s.object.size.x()) + " x " +
                 std::to_string(s.object.size.y()) + " x " + std::to_string(s.object.size.z()));
    const SceneSegmentation sa = gen.segmentScene(all.points), sb = gen.segmentScene(read.points);
    ASSERT_TRUE(sa.plane_found && sb.plane_found);
    EXPECT_LT(angleToAxis(sa.plane.head<3>(), sb.plane.head<3>()), 2.0 * kDeg);
    EXPECT_NEAR(sa.plane[3], sb.plane[3], 0.005);
    const Cluster ca = nearestCluster(sa, s.object), cb = nearestCluster(sb, s.object);
    EXPECT_LT((ca.centroid - cb.centroid).norm(), 0.02);
    EXPECT_LT((ca.lo - cb.lo).cwiseAbs().maxCoeff(), 0.01) << ca.lo.transpose() << " / " << cb.lo.transpose();
    EXPECT_LT((ca.hi - cb.hi).cwiseAbs().maxCoeff(), 0.01) << ca.hi.transpose() << " / " << cb.hi.transpose();
    const Eigen::Vector3d centre = s.object.pose.translation(), eye = s.camera.translation();
    const GraspResult a = generateForTarget(gen, all.points, eye, &centre, whole);
    const GraspResult b = generateForTarget(gen, read.points, eye, &centre, budgeted);
    EXPECT_EQ(b.budget_points, static_cast<int>(read.points.size()));
    EXPECT_EQ(a.grasps.empty(), b.grasps.empty()) << a.reason << " / " << b.reason;
    std::printf("scene %d: centroids %.4f m apart, extents within %.4f m; %zu / %zu grasps\n", k,
                (ca.centroid - cb.centroid).norm(),
                std::max((ca.lo - cb.lo).cwiseAbs().maxCoeff(), (ca.hi - cb.hi).cwiseAbs().maxCoeff()),
                a.grasps.size(), b.grasps.size());
  }
}

namespace {

/// The true object's extent along the grasp's closing axis between its fully open fingers: the
/// noise-free surface's points in the fingers' slab (finger breadth across x, finger length
/// along z), in the grasp frame (first the -y end, then the +y end; the grasp centre at 0).
std::pair<double, double> trueSpanBetweenFingers(const Grasp& g, const GripperGeometry& gr, const PointList& truth) {
  const Eigen::Isometry3d T = g.pose.inverse();
  double lo = std::numeric_limits<double>::max(), hi = -lo;
  for (const auto& pf : truth) {
    const Eigen::Vector3d p = T * pf.cast<double>();
    if (std::abs(p.x()) > 0.5 * gr.finger_breadth || p.z() > gr.finger_tip_depth ||
        p.z() < gr.finger_tip_depth - gr.finger_length || std::abs(p.y()) > 0.5 * gr.max_width)
      continue;
    lo = std::min(lo, p.y());
    hi = std::max(hi, p.y());
  }
  return {lo, hi};
}

/// trueSpanBetweenFingers' length.
double trueWidthBetweenFingers(const Grasp& g, const GripperGeometry& gr, const PointList& truth) {
  const std::pair<double, double> span = trueSpanBetweenFingers(g, gr, truth);
  return span.second - span.first;
}

enum class Solid { Box, StandingCylinder, LyingCylinder };
const char* solidName(Solid s) {
  return s == Solid::Box ? "box" : s == Solid::StandingCylinder ? "standing cylinder" : "lying cylinder";
}

/// A solid `width` m across (box: width x 0.10 x 0.08 m; cylinders 0.10 m long) resting on
/// the support z = 0 at (0.6, 0) with yaw `yaw`; the bottom is not sampled.
Surface solidOnSupport(Solid s, double width, double yaw, double step) {
  const double r = 0.5 * width;
  Surface out;
  Eigen::Isometry3d T;
  switch (s) {
    case Solid::Box:
      out = boxSurface(Eigen::Vector3d(width, 0.10, 0.08), step);
      T = pose(0.6, 0.0, 0.04, yaw);
      break;
    case Solid::StandingCylinder:
      out = cylinderSurface(r, -0.05, 0.05, step, false, true);
      T = pose(0.6, 0.0, 0.05, yaw);
      break;
    case Solid::LyingCylinder:
      out = cylinderSurface(r, -0.05, 0.05, step, true, true);
      T = pose(0.6, 0.0, r, yaw, 90 * kDeg);
      break;
  }
  out.transform(T);
  return out;
}

}  // namespace

// Widths measured between the fingers on random boxes and cylinders 20-80 mm across, under
// 0-3 mm noise, sampled all round or seen from one random view (30-60 deg above the support,
// 0.5 m away). Where the best grasp's two contacts are seen (fitted contact surfaces) its
// measured width is within 2 mm + 1 x the noise of the true object's extent between its
// fingers (the worst on this seed: 4.5 mm short on a box under 2.9 mm noise whose closing
// axis cuts a corner); objects 73 mm and wider are refused as too wide, except boxes seen from
// one view. Grasps with an unseen contact (a box's far face from one view, bounded by its top
// face's last samples and the object's extent) are printed, not asserted: they are off by up
// to 12 mm on this seed, and a 74 mm box is given a grasp measured 57 mm.
TEST(GraspWidths, RandomSolidsAreMeasuredBetweenTheFingersWithinTolerance) {
  const unsigned seed = 20261127;
  std::printf("seed %u\n", seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> width(0.020, 0.080), noise(0.0, 0.003), unit(0.0, 1.0);
  const GraspGeneratorConfig cfg;
  const GraspGenerator gen(cfg);
  const GripperGeometry& gr = cfg.gripper;
  double worst = 0.0;
  int grasped = 0, refused = 0;
  for (int trial = 0; trial < 48; ++trial) {
    const Solid solid = static_cast<Solid>(trial % 3);
    const bool one_view = (trial / 3) % 2 == 1;
    const double w = width(rng), sigma = noise(rng), yaw = 2 * M_PI * unit(rng);
    const double az = 2 * M_PI * unit(rng), el = (30 + 30 * unit(rng)) * kDeg;
    const Surface truth = solidOnSupport(solid, w, yaw, 0.002);
    const Eigen::Vector3d centre(0.6, 0.0, 0.03);
    const Eigen::Vector3d view =
        one_view ? Eigen::Vector3d(centre + 0.5 * Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)))
                 : kView;
    const Surface seen = one_view ? truth.visibleFrom(view) : truth;
    const GraspResult r = gen.generate(seen.noisy(sigma, seed + static_cast<unsigned>(trial)), view);
    const std::string what = std::string(solidName(solid)) + " " + std::to_string(1e3 * w) + " mm, noise " +
                             std::to_string(1e3 * sigma) + " mm, " + (one_view ? "one view" : "all round");
    SCOPED_TRACE(what);
    if (w >= 0.073 && !(one_view && solid == Solid::Box)) {
      EXPECT_TRUE(r.grasps.empty());
      EXPECT_EQ(toString(r.failure), "too_wide") << r.reason;
    }
    if (r.grasps.empty()) {
      ++refused;
      std::printf("%s: no grasp (%s)\n", what.c_str(), toString(r.failure).c_str());
      continue;
    }
    ++grasped;
    const Grasp& best = r.grasps.front();
    const double truth_w = trueWidthBetweenFingers(best, gr, truth.points);
    if (best.seen_contacts == 2) {
      EXPECT_NEAR(best.measured_width, truth_w, 0.002 + sigma);
      worst = std::max(worst, std::abs(best.measured_width - truth_w));
    }
    EXPECT_NEAR(best.width, best.measured_width + 2 * gr.clearance, 1e-9);
    std::printf("%s: measured %.1f mm, true %.1f mm between the fingers, %d contacts seen\n", what.c_str(),
                1e3 * best.measured_width, 1e3 * truth_w, best.seen_contacts);
  }
  std::printf("%d grasped, %d refused, largest width error with both contacts seen %.2f mm\n", grasped, refused,
              1e3 * worst);
  RecordProperty("largest_width_error_mm", std::to_string(1e3 * worst));
}

// A 66 mm cylinder, lying or standing on the support, sampled all round or seen from one random
// view (30-60 deg above the support, 0.5-0.7 m away), under 2 mm noise: its best grasp is
// measured 66 +- 2 mm and accepted (the extreme points after trimming measured it 75 mm).
// Seen from one view it is printed, not asserted: on this seed two of three lying views are
// refused (their sections' circles do not fit) and one standing view measures 62.8 mm.
TEST(GraspWidths, A66mmCylinderUnder2mmNoiseIsMeasured66mm) {
  const unsigned seed = 66;
  std::printf("seed %u\n", seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const GraspGenerator gen{GraspGeneratorConfig()};
  for (int trial = 0; trial < 12; ++trial) {
    const Solid solid = trial % 2 == 0 ? Solid::LyingCylinder : Solid::StandingCylinder;
    const bool one_view = (trial / 2) % 2 == 1;
    const double yaw = 2 * M_PI * unit(rng);
    const Surface truth = solidOnSupport(solid, 0.066, yaw, 0.002);
    const double az = 2 * M_PI * unit(rng), el = (30 + 30 * unit(rng)) * kDeg, dist = 0.5 + 0.2 * unit(rng);
    const Eigen::Vector3d centre(0.6, 0.0, 0.03);
    const Eigen::Vector3d view =
        one_view ? Eigen::Vector3d(centre + dist * Eigen::Vector3d(std::cos(el) * std::cos(az),
                                                                   std::cos(el) * std::sin(az), std::sin(el)))
                 : kView;
    const Surface seen = one_view ? truth.visibleFrom(view) : truth;
    const GraspResult r = gen.generate(seen.noisy(0.002, seed + static_cast<unsigned>(trial)), view);
    const std::string what = std::string(solidName(solid)) + (one_view ? ", one view" : ", all round") +
                             (one_view ? " (" + std::to_string(static_cast<int>(el / kDeg)) + " deg above, " +
                                             std::to_string(static_cast<int>(std::lround((az - yaw) / kDeg) % 180)) + " deg)"
                                       : std::string());
    SCOPED_TRACE(what);
    if (one_view && r.grasps.empty()) {
      std::printf("%s: no grasp (%s)\n", what.c_str(), r.reason.c_str());
      continue;
    }
    ASSERT_FALSE(r.grasps.empty()) << r.reason;
    if (!one_view) {
      EXPECT_NEAR(r.grasps.front().measured_width, 0.066, 0.002);
    }
    const Grasp& best = r.grasps.front();
    std::printf("%s: measured %.1f mm (true %.1f mm between the fingers), %d contacts seen, approach %s\n",
                what.c_str(), 1e3 * best.measured_width,
                1e3 * trueWidthBetweenFingers(best, GraspGeneratorConfig().gripper, truth.points), best.seen_contacts,
                [&] { std::ostringstream os; os << best.pose.linear().col(2).transpose(); return os.str(); }().c_str());
  }
}

// Random bent tubes (banana-like: 28-44 mm across, bent round 0.12-0.30 m, 0.14-0.22 m long)
// lying on the support at a random yaw, seen once from a random side 30-60 deg above the
// support, 0.45-0.6 m away, under 1.5 mm noise. The round cross-section where the fingers close
// completes the unseen far side (the section is taken within a finger's breadth of the middle,
// so the bend does not smear it): nearly every view gives a grasp across the tube, their median
// width within 6 mm of the diameter (single grasps are printed: where the best grasp is not on
// the middle's section its unseen side is bounded by the tube's extent, up to 22 mm wide on
// seed 1; the median was at most 4.5 mm on seeds 100-159). Fitting the whole body's section
// instead (the bend smears it: no circle fits), the unseen side was bounded by the tube's
// extent, a median error of 8-14 mm on seeds 100-129;
// on the object library's bananas seen along their length the sides, seen at grazing angles
// only, were refused as slanted contacts and there was no grasp at all.
TEST(GraspParts, ALyingBentTubeIsGraspedAcrossItsRoundSection) {
  const unsigned seed = ehc_test::testSeed("GraspParts bent tube");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const GraspGenerator gen{GraspGeneratorConfig()};
  constexpr int kViews = 24;
  int across = 0;
  std::vector<double> errors;
  for (int v = 0; v < kViews; ++v) {
    const double r = 0.014 + 0.008 * unit(rng), bend = 0.12 + 0.18 * unit(rng), length = 0.14 + 0.08 * unit(rng);
    const double yaw = 2 * M_PI * unit(rng), az = 2 * M_PI * unit(rng), el = (30 + 30 * unit(rng)) * kDeg;
    const double dist = 0.45 + 0.15 * unit(rng);
    const Eigen::Isometry3d T = pose(0.6, 0.0, r, yaw);
    Surface tube = bentTubeSurface(r, bend, length, 0.002);
    tube.transform(T);
    const Eigen::Vector3d centre(0.6, 0.0, r);
    const Eigen::Vector3d view = centre + dist * Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    const GraspResult res = gen.generate(tube.occludedFrom(view).noisy(0.0015, seed + static_cast<unsigned>(v)), view);
    std::string what = "view " + std::to_string(v) + ": r " + std::to_string(1e3 * r) + " mm, bend " + std::to_string(bend) +
                       " m, azimuth from the tube " + std::to_string(std::fmod(az - yaw + 4 * M_PI, 2 * M_PI) / kDeg) + " deg";
    if (res.grasps.empty()) {
      std::printf("%s: no grasp (%s)\n", what.c_str(), res.reason.c_str());
      continue;
    }
    const Grasp& best = res.grasps.front();
    expectValidFrame(best);
    expectAboveTable(best, 0.0);
    // The centre line's tangent nearest the grasp: across the tube when the closing axis is
    // within 30 deg of the section's plane.
    double nearest = 1e9;
    Eigen::Vector3d tangent = Eigen::Vector3d::UnitX();
    for (int k = -100; k <= 100; ++k) {
      const double t = 0.5 * length / bend * k / 100.0;
      const Eigen::Vector3d c = T * Eigen::Vector3d(bend * std::sin(t), bend * (1.0 - std::cos(t)), 0.0);
      if ((c - best.pose.translation()).norm() < nearest) {
        nearest = (c - best.pose.translation()).norm();
        tangent = T.linear() * Eigen::Vector3d(std::cos(t), std::sin(t), 0.0);
      }
    }
    const bool is_across = std::abs(best.pose.linear().col(1).dot(tangent)) < std::sin(30 * kDeg);
    std::printf("%s: %s, measured %.1f mm (diameter %.1f), %d contacts seen\n", what.c_str(),
                is_across ? "across" : "not across", 1e3 * best.measured_width, 2e3 * r, best.seen_contacts);
    if (!is_across) continue;
    ++across;
    errors.push_back(std::abs(best.measured_width - 2 * r));
  }
  std::printf("seed %u: %d of %d views grasped across the tube\n", seed, across, kViews);
  EXPECT_GE(across, kViews - 2);
  ASSERT_FALSE(errors.empty());
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  EXPECT_LE(errors[errors.size() / 2], 0.006) << "median width error";
}

// A 90 mm ball gives no grasp, the reason too wide, from all round and from one view (one
// view shows less than half of it: its sphere measures it).
TEST(GraspWidths, A90mmBallIsTooWide) {
  Surface ball = sphereSurface(0.045, 0.003);
  ball.transform(pose(0.6, 0.0, 0.045, 0.0));
  const GraspGenerator gen{GraspGeneratorConfig()};
  const Eigen::Vector3d side_view(0.25, 0.1, 0.3);
  for (unsigned seed : {1u, 2u}) {
    std::printf("seed %u\n", seed);
    for (const Eigen::Vector3d& view : {kView, side_view}) {
      const Surface seen = view == kView ? ball : ball.visibleFrom(view);
      const GraspResult r = gen.generate(seen.noisy(0.0015, seed), view);
      EXPECT_TRUE(r.grasps.empty()) << r.grasps.size() << " grasps, the widest "
                                    << (r.grasps.empty() ? 0.0 : r.grasps.front().width);
      EXPECT_EQ(r.failure, GraspFailure::TooWide) << r.reason;
      EXPECT_NE(r.reason.find("too wide"), std::string::npos) << r.reason;
    }
  }
}

TEST(GraspWidths, FailureNamesRoundTrip) {
  for (GraspFailure f : {GraspFailure::None, GraspFailure::TooWide, GraspFailure::NoAntipodalPair,
                         GraspFailure::TargetTooFar})
    EXPECT_EQ(graspFailureFromString(toString(f)), f);
  EXPECT_THROW(graspFailureFromString("wide"), std::invalid_argument);
}

namespace {

/// The handle's and the rim's parts of the mug of mugSurface (body radius r, wall, height, the
/// handle's bar radius and reach), at the origin: is the point `p` on the handle, or within
/// `tol` of the rim's annulus?
bool onHandleOrRim(const Eigen::Vector3d& p, double r, double wall, double height, double tol) {
  const double rho = std::hypot(p.x(), p.y());
  const bool handle = p.x() > r - tol && std::abs(p.y()) < 0.03;
  const bool rim = std::abs(p.z() - height) < 0.03 && rho > r - wall - tol && rho < r + tol;
  return handle || rim;
}

}  // namespace

namespace {

constexpr double kNoise = 0.0015;  ///< m, the depth noise of the wall grasps' tests

/// Points of `truth` inside either finger of `g` opened to its width by more than `depth` (the
/// fingers' boxes: 10 mm thick beyond +-width / 2, finger_breadth across, finger_length along the
/// approach; `depth`: what the measurement's noise may leave of a seen contact in its finger).
int pointsInFingers(const Grasp& g, const GripperGeometry& gr, const PointList& truth, double depth) {
  const Eigen::Isometry3d T = g.pose.inverse();
  int n = 0;
  for (const auto& pf : truth) {
    const Eigen::Vector3d p = T * pf.cast<double>();
    const double ay = std::abs(p.y());
    n += std::abs(p.x()) <= 0.5 * gr.finger_breadth && p.z() <= gr.finger_tip_depth &&
         p.z() >= gr.finger_tip_depth - gr.finger_length && ay > 0.5 * g.width + depth &&
         ay < 0.5 * g.width + gr.finger_thickness;
  }
  return n;
}

/// A camera 0.5-0.7 m from `centre`, 30-60 deg above the support, any azimuth.
Eigen::Vector3d randomView(const Eigen::Vector3d& centre, std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double az = 2 * M_PI * unit(*rng), el = (30 + 30 * unit(*rng)) * kDeg, dist = 0.5 + 0.2 * unit(*rng);
  return centre + dist * Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
}

}  // namespace

// A mug whose body is 90 mm wide (the gripper opens 70 mm) standing on the support, sampled
// all round or seen from one view from the handle's side (occlusion by z-buffer) under 1.5 mm
// noise: where it is grasped, it is on its handle or its rim and across the part (the true
// surface between the fingers narrower than the opening), never across the body; a wall grasp
// across the body's wall, nothing of the mug more than the noise inside its fingers. Every
// trial of this seed is grasped: one all-round cloud on its handle, the others by wall grasps.
TEST(GraspParts, A90mmMugIsGraspedOnlyByItsHandleOrRim) {
  const unsigned seed = 90;
  std::printf("seed %u\n", seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const GraspGeneratorConfig cfg;
  const GraspGenerator gen(cfg);
  const double r = 0.045, wall = 0.006, height = 0.095;
  for (int trial = 0; trial < 6; ++trial) {
    const double yaw = 2 * M_PI * unit(rng);
    Surface truth = mugSurface(r, wall, height, 0.006, 0.025, 0.002);
    const Eigen::Isometry3d T = pose(0.6, 0.0, 0.0, yaw);
    truth.transform(T);
    const bool one_view = trial % 2 == 1;
    // One view: from the handle's side (within 60 deg of it), 30-60 deg above the support.
    const double az = yaw + (unit(rng) - 0.5) * 120 * kDeg, el = (30 + 30 * unit(rng)) * kDeg;
    const Eigen::Vector3d view = one_view ? Eigen::Vector3d(Eigen::Vector3d(0.6, 0.0, 0.05) +
                                                            0.6 * Eigen::Vector3d(std::cos(el) * std::cos(az),
                                                                                  std::cos(el) * std::sin(az), std::sin(el)))
                                          : kView;
    const Surface seen = one_view ? truth.occludedFrom(view) : truth;
    const GraspResult res = gen.generate(seen.noisy(0.0015, seed + static_cast<unsigned>(trial)), view);
    SCOPED_TRACE(std::string(one_view ? "one view" : "all round") + ", trial " + std::to_string(trial));
    if (res.grasps.empty()) {
      std::printf("trial %d (%s): no grasp, %s: %s\n", trial, one_view ? "one view" : "all round",
                  toString(res.failure).c_str(), res.reason.c_str());
      continue;
    }
    const Grasp& best = res.grasps.front();
    const Eigen::Vector3d local = T.inverse() * best.pose.translation();
    // A wall grasp closes across the body's wall (from its top down to finger_length - its
    // fingertip depth below it), its centre between its seen contact and the far finger's bound:
    // the wall is what is between its fingers, and nothing of the mug inside them.
    if (best.wall) {
      EXPECT_LT(trueWidthBetweenFingers(best, cfg.gripper, truth.points), 3.0 * wall);
      EXPECT_EQ(pointsInFingers(best, cfg.gripper, truth.points, kNoise), 0);
    } else {
      EXPECT_TRUE(onHandleOrRim(local, r, wall, height, 0.012)) << "grasp at " << local.transpose();
    }
    EXPECT_LT(trueWidthBetweenFingers(best, cfg.gripper, truth.points), cfg.gripper.max_width);
    std::printf("trial %d (%s): %zu grasps, best at (%.3f %.3f %.3f) in the mug's frame, measured %.1f mm, %d seen\n",
                trial, one_view ? "one view" : "all round", res.grasps.size(), local.x(), local.y(), local.z(),
                1e3 * best.measured_width, best.seen_contacts);
  }
}

// A roof-shaped prism (faces 45 deg from the horizontal, 60 mm wide, lying on the support):
// the only closings that fit the opening touch its faces 45 deg off the closing axis, outside
// the friction cone of mu 0.5 (26.6 deg): no grasp, the reason counting the poses refused for
// friction; with mu 1.2 (50 deg) the same cloud is grasped (only mu differs).
TEST(GraspContacts, AContactPair45DegOffIsRefusedWithMu05) {
  Surface roof = roofPrismSurface(0.060, 0.12, 0.002);
  roof.transform(pose(0.6, 0.0, 0.0, 0.4));
  GraspGeneratorConfig cfg;
  cfg.friction_coefficient = 0.5;
  const GraspGenerator gen(cfg);
  for (unsigned seed : {1u, 2u}) {
    std::printf("seed %u\n", seed);
    for (const Eigen::Vector3d& view : {kView, Eigen::Vector3d(0.3, -0.3, 0.45)}) {
      const Surface seen = view == kView ? roof : roof.visibleFrom(view);
      const GraspResult r = gen.generate(seen.noisy(0.001, seed), view);
      for (const Grasp& g : r.grasps)
        std::printf("grasp: closing %s, measured %.1f mm, %d seen\n",
                    [&] { std::ostringstream os; os << g.pose.linear().col(1).transpose(); return os.str(); }().c_str(),
                    1e3 * g.measured_width, g.seen_contacts);
      EXPECT_TRUE(r.grasps.empty()) << r.grasps.size() << " grasps";
      EXPECT_NE(r.reason.find("friction cone"), std::string::npos) << r.reason;
      std::printf("no grasp: %s (%s)\n", toString(r.failure).c_str(), r.reason.c_str());
    }
  }
  cfg.friction_coefficient = 1.2;
  const GraspResult r = GraspGenerator(cfg).generate(roof.noisy(0.001, 1), kView);
  EXPECT_FALSE(r.grasps.empty()) << r.reason;
}


/// A randomized wall-grasp test's draws: the printed seed, its stream, uniform [0, 1) draws, and
/// the default generator.
struct WallGraspTrials {
  explicit WallGraspTrials(const char* name) : seed(ehc_test::testSeed(name)), rng(seed) {}
  double unit() { return std::uniform_real_distribution<double>(0.0, 1.0)(rng); }
  unsigned seed;
  std::mt19937 rng;
  GraspGeneratorConfig cfg;
  GraspGenerator gen{cfg};
  /// A random cup: rim radius r 50-80 mm, its wall `wall_min` + `wall_span` x U thick, 40-80 mm
  /// high, on odd trials flared at the rim by 40-55 % of r; turned at random about its axis at
  /// (0.6, 0, 0); and a random view of its middle.
  struct Cup {
    double r = 0.0, wall = 0.0, height = 0.0, flare = 0.0;
    Surface truth;
    Eigen::Vector3d view = Eigen::Vector3d::Zero();
    std::string what() const {
      return "r " + std::to_string(1e3 * r) + " mm, wall " + std::to_string(1e3 * wall) + " mm, height " +
             std::to_string(1e3 * height) + " mm, flare " + std::to_string(1e3 * flare) + " mm, view " +
             std::to_string(view.x()) + " " + std::to_string(view.y()) + " " + std::to_string(view.z());
    }
  };
  Cup cup(int trial, double wall_min, double wall_span) {
    Cup c;
    c.r = 0.05 + 0.03 * unit();
    c.wall = wall_min + wall_span * unit();
    c.height = 0.04 + 0.04 * unit();
    c.flare = trial % 2 == 0 ? 0.0 : (0.4 + 0.15 * unit()) * c.r;
    c.truth = cupSurface(c.r, c.wall, c.height, 0.002, c.flare);
    c.truth.transform(pose(0.6, 0.0, 0.0, 2 * M_PI * unit()));
    c.view = randomView(Eigen::Vector3d(0.6, 0.0, 0.5 * c.height), &rng);
    return c;
  }
};

// Random cups 100-160 mm across (wider than the opening), walls 3-6 mm, 40-80 mm high, seen
// once from a random view under 1.5 mm noise: no wall is seen from both sides, yet there are
// wall grasps across the rim: the true cup between the fingers of the best of them is the wall
// (at most 3 x its thickness); under none of them is the cup under-measured (the true surface
// between the fingers within the measured width + the noise) or inside a finger. How often a
// wall grasp is the best grasp is printed.
TEST(WallGrasps, ARandomCupsRimIsGraspedAcrossItsWallFromOneView) {
  WallGraspTrials t("WallGrasps random cups");
  // Every grasp kept (not the top 10): other grasps on the rim may outrank the wall grasps, and
  // the claim is that wall grasps exist and are right, not that they rank first.
  t.cfg.top_k = 200;
  t.gen = GraspGenerator(t.cfg);
  int best_wall = 0;
  for (int trial = 0; trial < 6; ++trial) {
    const double r = 0.05 + 0.03 * t.unit(), wall = 0.003 + 0.003 * t.unit(), height = 0.04 + 0.04 * t.unit();
    Surface truth = cupSurface(r, wall, height, 0.002);
    truth.transform(pose(0.6, 0.0, 0.0, 2 * M_PI * t.unit()));
    const Eigen::Vector3d view = randomView(Eigen::Vector3d(0.6, 0.0, 0.5 * height), &t.rng);
    const GraspResult res = t.gen.generate(truth.occludedFrom(view).noisy(kNoise, t.seed + static_cast<unsigned>(trial)), view);
    const std::string what = "cup r " + std::to_string(1e3 * r) + " mm, wall " + std::to_string(1e3 * wall) +
                             " mm, height " + std::to_string(1e3 * height) + " mm, view " +
                             std::to_string(view.x()) + " " + std::to_string(view.y()) + " " + std::to_string(view.z());
    SCOPED_TRACE(what);
    const Grasp* first = nullptr;
    for (const Grasp& g : res.grasps) {
      if (!g.wall) continue;
      if (!first) first = &g;
      EXPECT_LE(trueWidthBetweenFingers(g, t.cfg.gripper, truth.points), g.measured_width + kNoise);
      EXPECT_EQ(pointsInFingers(g, t.cfg.gripper, truth.points, kNoise), 0);
    }
    ASSERT_NE(first, nullptr) << res.reason;
    best_wall += res.grasps.front().wall;
    const double between = trueWidthBetweenFingers(*first, t.cfg.gripper, truth.points);
    std::printf("%s: best grasp %s; best wall grasp measured %.1f mm, true %.1f mm between the fingers\n", what.c_str(),
                res.grasps.front().wall ? "a wall grasp" : "not a wall grasp", 1e3 * first->measured_width, 1e3 * between);
    EXPECT_LT(between, 3.0 * wall);
  }
  std::printf("the best grasp is a wall grasp in %d of 6 views\n", best_wall);
}

// Random thin-walled cups and bowls (rims 100-160 mm across, walls 2.5-6 mm, 40-80 mm high;
// the bowls' bases 45-60 % of the rim's radius, their walls curving in below a vertical rim)
// seen once from a random view under 1.5 mm noise: the far finger's bound lies where the view's
// shadow behind the rim ends, 10-30 mm or more beyond the wall, yet every wall grasp is centred
// on the wall (the middle of the true surface between its fingers within 3.5 mm of the grasp
// centre along the closing axis) or, where the bound lies more than half the opening beyond
// that middle, as near it as the opening allows (the far finger fully open at the bound), so
// that a symmetric close reaches both faces together instead of pushing the object with one
// finger. How many wall grasps are centred on the wall is printed. The earlier centre, midway
// between the seen contact and the bound, was 10-28 mm off.
TEST(WallGrasps, AThinWallsRimGraspIsCentredOnTheWallNotOnTheShadow) {
  WallGraspTrials t("WallGrasps centred on thin walls");
  const double kCentred = 0.0035;  ///< m
  int checked = 0;
  double worst = 0.0;
  for (int trial = 0; trial < 8; ++trial) {
    const WallGraspTrials::Cup cup = t.cup(trial, 0.0025, 0.0035);
    const Surface& truth = cup.truth;
    const GraspResult res =
        t.gen.generate(truth.occludedFrom(cup.view).noisy(kNoise, t.seed + static_cast<unsigned>(trial)), cup.view);
    const std::string what = cup.what();
    SCOPED_TRACE(what);
    int walls = 0, centred = 0;
    for (const Grasp& g : res.grasps) {
      if (!g.wall) continue;
      ++walls;
      const std::pair<double, double> span = trueSpanBetweenFingers(g, t.cfg.gripper, truth.points);
      const double middle = 0.5 * (span.first + span.second);
      // Where the centre belongs: the wall's middle, or, the far finger's bound (measured from
      // the seen contact on -y, within twice the noise of the true surface) more than half the
      // opening beyond it, half the opening short of the bound (nearer the bound than the middle).
      const double bound = span.first + g.measured_width + t.cfg.gripper.clearance;
      const double short_of_bound = std::abs(bound - 0.5 * t.cfg.gripper.max_width);
      const bool at_middle = std::abs(middle) < kCentred;
      EXPECT_TRUE(at_middle || (middle < 0.0 && short_of_bound < kCentred + 2.0 * kNoise))
          << "true surface between the fingers " << 1e3 * span.first << " to " << 1e3 * span.second
          << " mm, measured " << 1e3 * g.measured_width << " mm";
      EXPECT_LE(span.second - span.first, g.measured_width + kNoise);
      EXPECT_EQ(pointsInFingers(g, t.cfg.gripper, truth.points, kNoise), 0);
      centred += at_middle;
      if (at_middle) worst = std::max(worst, std::abs(middle));
    }
    checked += walls;
    std::printf("%s: %d wall grasps, %d centred on the wall\n", what.c_str(), walls, centred);
  }
  std::printf("%d wall grasps checked, those centred on the wall at most %.1f mm off\n", checked, 1e3 * worst);
  EXPECT_GT(checked, 0);
}

// Random cups and bowls (rims 100-160 mm across) seen once from a random view under 1.5 mm
// noise: besides the straight-down wall grasps there are wall grasps approached wall_tilt_deg
// from straight down about their closing axis (the closing axis horizontal, the approach's
// horizontal part away from the camera: the hand from the viewer's side), and each passes the
// straight-down ones' checks (the true cup between the fingers within the measured width +
// the noise, nothing of it inside a finger); with wall_tilt_deg 0 every wall grasp is
// approached straight down. An arm mounted below the table's top reaches the rims of a bowl in
// the middle of the table only with such a tilt (test_grasp_reach).
TEST(WallGrasps, ARimIsAlsoGraspedWithTheApproachTiltedTowardsTheViewer) {
  WallGraspTrials t("WallGrasps tilted towards the viewer");
  t.cfg.top_k = 200;
  const Eigen::Vector3d up = t.cfg.up.normalized();
  int tilted_total = 0;
  for (int trial = 0; trial < 6; ++trial) {
    const WallGraspTrials::Cup cup = t.cup(trial, 0.003, 0.003);
    const Surface& truth = cup.truth;
    const Eigen::Vector3d& view = cup.view;
    const PointList seen = truth.occludedFrom(view).noisy(kNoise, t.seed + static_cast<unsigned>(trial));
    SCOPED_TRACE(cup.what());
    int tilted = 0, straight = 0;
    for (const Grasp& g : GraspGenerator(t.cfg).generate(seen, view).grasps) {
      if (!g.wall) continue;
      const Eigen::Vector3d a = g.pose.linear().col(2), y = g.pose.linear().col(1);
      const double tilt = std::acos(std::clamp(-a.dot(up), -1.0, 1.0)) / kDeg;
      EXPECT_NEAR(y.dot(up), 0.0, 1e-9);
      if (tilt < 0.01) {
        ++straight;
        continue;
      }
      ++tilted;
      EXPECT_NEAR(tilt, t.cfg.wall_tilt_deg, 0.01);
      const Eigen::Vector3d from_view = g.pose.translation() - view;
      EXPECT_GE((a - a.dot(up) * up).dot(from_view - from_view.dot(up) * up), 0.0);
      EXPECT_LE(trueWidthBetweenFingers(g, t.cfg.gripper, truth.points), g.measured_width + kNoise);
      EXPECT_EQ(pointsInFingers(g, t.cfg.gripper, truth.points, kNoise), 0);
    }
    std::printf("trial %d: %d straight-down and %d tilted wall grasps\n", trial, straight, tilted);
    EXPECT_GT(tilted, 0);
    tilted_total += tilted;
    GraspGeneratorConfig down = t.cfg;
    down.wall_tilt_deg = 0.0;
    for (const Grasp& g : GraspGenerator(down).generate(seen, view).grasps) {
      if (g.wall) {
        EXPECT_GT(-g.pose.linear().col(2).dot(up), std::cos(0.01 * kDeg));
      }
    }
  }
  EXPECT_GT(tilted_total, 0);
}

// Random lying and standing cylinders 15-90 mm across seen once under 1.5 mm noise: every wall
// grasp's measured width holds the true cylinder between its fingers (never under-measured,
// within the noise), no true surface point is inside a finger, and a cylinder wider than the
// opening gets none.
TEST(WallGrasps, ARandomCylindersWidthIsNeverUnderMeasured) {
  WallGraspTrials t("WallGrasps random cylinders");
  int walls = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const Solid solid = trial % 2 == 0 ? Solid::LyingCylinder : Solid::StandingCylinder;
    const double w = 0.015 + 0.075 * t.unit();
    const Surface truth = solidOnSupport(solid, w, 2 * M_PI * t.unit(), 0.002);
    const Eigen::Vector3d view = randomView(Eigen::Vector3d(0.6, 0.0, 0.03), &t.rng);
    const GraspResult res = t.gen.generate(truth.visibleFrom(view).noisy(kNoise, t.seed + static_cast<unsigned>(trial)), view);
    const std::string what = std::string(solidName(solid)) + " " + std::to_string(1e3 * w) + " mm";
    SCOPED_TRACE(what);
    for (const Grasp& g : res.grasps) {
      if (!g.wall) continue;
      ++walls;
      const double between = trueWidthBetweenFingers(g, t.cfg.gripper, truth.points);
      std::printf("%s: wall grasp measured %.1f mm, true %.1f mm between the fingers\n", what.c_str(),
                  1e3 * g.measured_width, 1e3 * between);
      EXPECT_LT(w, t.cfg.gripper.max_width);
      EXPECT_LE(between, g.measured_width + kNoise);
      EXPECT_EQ(pointsInFingers(g, t.cfg.gripper, truth.points, kNoise), 0);
    }
  }
  std::printf("%d wall grasps checked\n", walls);
}

namespace {

/// A box standing on a table (top at `table_z`) at (0.7, 0), turned by `yaw`: its pose and size,
/// the depth camera's boxes (table and box) and the box's true surface.
struct BoxOnTable {
  Box box;
  std::vector<Box> scene;
  Surface truth;
};
BoxOnTable boxOnTable(const Eigen::Vector3d& size, double yaw, double table_z) {
  BoxOnTable b;
  b.box.pose = pose(0.7, 0.0, table_z + 0.5 * size.z(), yaw);
  b.box.size = size;
  Box table;
  table.pose = pose(0.7, 0.0, table_z - 0.02, 0.0);
  table.size = Eigen::Vector3d(0.8, 1.2, 0.04);
  b.scene = {table, b.box};
  b.truth = boxSurface(size, 0.002, true);
  b.truth.transform(b.box.pose);
  return b;
}

/// Whether `box` runs out of the frame of depthCameraCloud's camera (`width` x `height` pixels) at
/// `cam`: a pixel on the frame's edge sees it (in front of everything else in `scene`) higher
/// than `above_z` (world). Below it (the support plane's points to the segmentation, its
/// plane_distance) the object's cluster ends anyway: a box whose bottom millimetres alone run
/// out of the frame is seen whole.
bool outOfFrame(const Box& box, const std::vector<Box>& scene, const Eigen::Isometry3d& cam, int width, int height,
                double above_z) {
  const double f = 615.0 * width / 640.0;
  const Eigen::Vector3d o = cam.translation();
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      if (u > 0 && u < width - 1 && v > 0 && v < height - 1) continue;
      const Eigen::Vector3d d = (cam.linear() * Eigen::Vector3d((u - 0.5 * width) / f, (v - 0.5 * height) / f, 1.0)).normalized();
      const double t = rayBox(o, d, box);
      bool first = std::isfinite(t) && (o + t * d).z() > above_z;
      for (const Box& b : scene) first = first && rayBox(o, d, b) >= t - 1e-9;
      if (first) return true;
    }
  return false;
}

/// A camera `dist` m from `at`, `el_deg` above the horizontal, from azimuth `az` (world), looking
/// at `at` + `aim` (its optical frame).
Eigen::Isometry3d cameraAt(const Eigen::Vector3d& at, double dist, double el_deg, double az, const Eigen::Vector3d& aim) {
  const double el = el_deg * kDeg;
  const Eigen::Vector3d eye = at + dist * Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  return lookAt(eye, at + aim);
}

}  // namespace

// A thin box (30-50 mm thick, 120-160 mm wide and high) standing on a table under 1.5 mm depth
// noise, its large face towards an 80 x 60 depth camera 0.3 m away (within 50 deg; the hand
// camera's close views) aimed 60-90 mm beside it, so that it runs out of the frame: the extent
// the view shows is short of the box, and every grasp for the tracked target has both contacts
// seen, measured within 2 mm + the noise of the true box between its fingers. The view's
// centroid lies near the large face: normals oriented away from it turned part of the face
// inwards (contact pairs 3-5 mm apart on one face); they face the camera. Aimed at the box (a
// 160 x 120 camera 0.4 m away), its grasps are kept.
TEST(GraspWidths, ATargetRunningOutOfTheFrameKeepsOnlyGraspsWithBothContactsSeen) {
  const unsigned seed = ehc_test::testSeed("GraspWidths target out of the frame");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const GraspGeneratorConfig cfg;
  const GraspGenerator gen(cfg);
  const GraspTargetingParams targeting;
  ehc_control::TargetSelector selector;
  selector.kind = ehc_control::TargetSelectorKind::Nearest;
  const double noise = 0.0015, table_z = 0.75;
  int cut_views = 0, cut_grasps = 0, whole_grasps = 0;
  for (int trial = 0; trial < 16; ++trial) {
    const Eigen::Vector3d size(0.03 + 0.02 * unit(rng), 0.12 + 0.04 * unit(rng), 0.12 + 0.04 * unit(rng));
    const double yaw = 2 * M_PI * unit(rng);
    const BoxOnTable b = boxOnTable(size, yaw, table_z);
    const Eigen::Vector3d centre = b.box.pose.translation();
    const double az = yaw + (unit(rng) < 0.5 ? 0.0 : M_PI) + (100 * unit(rng) - 50) * kDeg, el = 25 + 20 * unit(rng);
    const double off = 0.06 + 0.03 * unit(rng), turn = 2 * M_PI * unit(rng);
    const Eigen::Vector3d aside = off * Eigen::Vector3d(-std::sin(az) * std::cos(turn), std::cos(az) * std::cos(turn), std::sin(turn));
    selector.point = centre;
    const std::string what = "box " + std::to_string(1e3 * size.x()) + " mm thick, trial " + std::to_string(trial);
    SCOPED_TRACE(what);
    const Eigen::Isometry3d cut_cam = cameraAt(centre, 0.3, el, az, aside);
    const PointList cut = depthCameraCloud(80, 60, cut_cam, b.scene, noise, seed + static_cast<unsigned>(trial));
    const CloudTargetResult r = generateForCloudTarget(gen, cut, cut_cam, selector, &centre, targeting);
    if (outOfFrame(b.box, b.scene, cut_cam, 80, 60, table_z + cfg.plane_distance)) {
      ++cut_views;
      for (const Grasp& g : r.grasps.grasps) {
        ++cut_grasps;
        const double between = trueWidthBetweenFingers(g, cfg.gripper, b.truth.points);
        std::printf("%s, cut: measured %.1f mm, true %.1f mm, %d contacts seen\n", what.c_str(), 1e3 * g.measured_width,
                    1e3 * between, g.seen_contacts);
        EXPECT_EQ(g.seen_contacts, 2);
        EXPECT_NEAR(g.measured_width, between, 0.002 + noise);
      }
      if (r.grasps.grasps.empty()) std::printf("%s, cut: %s\n", what.c_str(), r.grasps.reason.c_str());
    }
    const Eigen::Isometry3d cam = cameraAt(centre, 0.4, el, az, Eigen::Vector3d::Zero());
    const PointList whole = depthCameraCloud(160, 120, cam, b.scene, noise, seed + static_cast<unsigned>(trial));
    whole_grasps += static_cast<int>(generateForCloudTarget(gen, whole, cam, selector, &centre, targeting).grasps.grasps.size());
  }
  std::printf("%d views cut by the frame (%d grasps), %d grasps of whole targets\n", cut_views, cut_grasps, whole_grasps);
  EXPECT_GT(cut_views, 0);
  EXPECT_GT(whole_grasps, 0);
}
