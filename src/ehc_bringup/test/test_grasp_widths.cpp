// Near-limit widths: objects up to 68 mm across the closing axis are grasped
// with the 70 mm gripper; 72 mm (held back) gives a clear "too wide" result.
//
// The scene is config/scenes/single_object.yaml (Exp-3, downward approach) with its object
// replaced by a box, a standing cylinder or a cylinder lying with its axis towards the robot, of
// width 60 ... 72 mm. Perception: single-view depth clouds rendered by the simulator's
// SimulatedCamera (its ray grid and depth noise, config/sim/bullet_sim.yaml) from views in
// front of and above the object, through generateForTarget as ehc_grasp_node runs it.
// Execution: the in-process GraspPipeline (Bullet) grasps and lifts the object, with
// require_candidate so the grasp comes from the generator (not the tag fallback).
#include "ehc_bringup/grasp_experiment.h"
#include "ehc_control/pinhole_camera.h"
#include "ehc_control/robot_config.h"
#include "ehc_perception/point_cloud_layout.h"
#include "ehc_perception/tag_detector.h"
#include "ehc_sim/sim_world.h"
#include "ehc_sim/simulated_camera.h"

// The perception tests' exact object surfaces (box, cylinder): the true geometry here.
#include "ehc_test/perception_fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

using namespace ehc_bringup;

namespace {

enum class Shape { Box, StandingCylinder, LyingCylinder };

std::string toString(Shape s) {
  switch (s) {
    case Shape::Box: return "box";
    case Shape::StandingCylinder: return "standing_cylinder";
    case Shape::LyingCylinder: return "lying_cylinder";
  }
  return "?";
}

constexpr double kTableTop = 0.70;   // single_object.yaml's table
constexpr double kLength = 0.12;     // height (standing) or length (lying)
constexpr int kTagId = 2;            // tag36h11 id 2: 3 cm in the demo's detector (fits every face)
constexpr double kTagSize = 0.03;
/// The robot starts 1.0 m from the object (Exp-3: 1.5 m): the 3 cm tag that fits every
/// object's face is not detected from 1.5 m (~12 px), and from 1.1 m the floor is still the
/// largest plane of the first clouds (the table top and the object are then one cluster).
/// Not nearer: the ready pose's hand camera looks 19 deg down, and from 0.9 m (the former start)
/// the tag on the lying cylinder's cap, 3-4 cm above the table, lay on the image's bottom edge
/// (with its white border rows 446 .. 483 of 480; on the top edge with the old upside-down
/// camera): cut, detected only by pixel luck (60 mm: never; 64-68 mm lost with the upright
/// camera). From 1.0 m its white border ends at row 420 (TheStartViewShowsTheWholeTag... below).
constexpr double kRobotStartX = 0.5;

GraspExperimentParams exp3Params() {
  GraspExperimentParams p;
  p.protocol = GraspProtocol::Poses;
  p.config_dir = EHC_CONFIG_DIR;
  p.sets = 1;
  p.per_set = 1;
  p.jitter_xy = 0.0;
  p.jitter_yaw_deg = 0.0;
  p.timing = false;
  return p;
}

/// Exp-3's downward configuration with the object replaced by `shape` `width` m across.
GraspPipelineConfig widthConfig(Shape shape, double width, unsigned seed) {
  const GraspExperiment exp(exp3Params(), {"ehc"});
  GraspPipelineConfig c = exp.runConfig("ehc", "downward", seed);
  ehc_sim::BodyConfig& o = c.scene.objects.at(0);
  o.tag.enabled = true;
  o.tag.id = kTagId;
  o.tag.size = kTagSize;
  o.rpy.setZero();
  const bool box = shape == Shape::Box, lying = shape == Shape::LyingCylinder;
  o.shape = box ? ehc_sim::ShapeType::Box : ehc_sim::ShapeType::Cylinder;
  o.size = box ? Eigen::Vector3d(width, width, kLength) : Eigen::Vector3d(width, kLength, 0.0);
  o.position.z() = kTableTop + 0.5 * (lying ? width : kLength);
  // Upright: tag on the side facing the robot. Lying: axis along world x (towards the robot),
  // tag upright on the cap facing the robot.
  if (lying) o.rpy = Eigen::Vector3d(0.0, -0.5 * M_PI, 0.0);
  o.tag.face = lying ? ehc_sim::Face::PosZ : ehc_sim::Face::NegX;
  const double tag_depth = 0.5 * (lying ? kLength : width);  // the object's centre behind the tag
  c.scene.robot_start.x() = kRobotStartX;
  c.scene.validate();
  c.tag_targets.at(0).tag_id = kTagId;
  c.tag_targets.at(0).offset_xyz = Eigen::Vector3d(0.0, 0.0, -tag_depth);
  c.sequencer.selection.require_candidate = true;
  return c;
}

/// The object's true surface (1 mm samples) in the world.
ehc_perception::test::Surface trueSurface(Shape shape, double width, const Eigen::Isometry3d& T_world_body) {
  using namespace ehc_perception::test;
  Surface s = shape == Shape::Box ? boxSurface(Eigen::Vector3d(width, width, kLength), 0.001, true)
                                  : cylinderSurface(0.5 * width, -0.5 * kLength, 0.5 * kLength, 0.001, true, true);
  s.transform(T_world_body);
  return s;
}

/// The open gripper's fingers span the object: the object's points in the fingers' slab (finger
/// breadth across x, finger length along z) lie between the inner faces of the fully open
/// fingers (+-max_width / 2 along y), with points on both sides of the grasp centre.
bool spansObject(const ehc_perception::Grasp& g, const ehc_perception::GripperGeometry& gripper,
                 const ehc_perception::PointList& surface) {
  const Eigen::Isometry3d T_grasp_world = g.pose.inverse();
  double lo = 0.0, hi = 0.0;
  for (const auto& pf : surface) {
    const Eigen::Vector3d p = T_grasp_world * pf.cast<double>();
    if (std::abs(p.x()) > 0.5 * gripper.finger_breadth) continue;
    if (p.z() > gripper.finger_tip_depth || p.z() < gripper.finger_tip_depth - gripper.finger_length) continue;
    lo = std::min(lo, p.y());
    hi = std::max(hi, p.y());
  }
  return lo < 0.0 && hi > 0.0 && hi <= 0.5 * gripper.max_width && lo >= -0.5 * gripper.max_width;
}

struct View {
  double distance, elevation_deg, azimuth_deg;  ///< from the object centre; azimuth 0 = from -x
};
const View kViews[] = {{0.35, 45.0, 0.0}, {0.45, 30.0, 10.0}, {0.60, 60.0, -15.0}};

struct PerceptionOutcome {
  int clouds = 0, spanning = 0, with_grasps = 0, too_wide = 0;
  std::string first_reason;
};

/// Renders each view x noise seed, runs the generator as ehc_grasp_node does, and counts the
/// clouds with at least one grasp whose finger axis spans the object (its true extent along the
/// closing axis lies between the fingers' inner faces, both sides).
PerceptionOutcome perceive(Shape shape, double width) {
  const GraspPipelineConfig cfg = widthConfig(shape, width, 1);
  const ehc_control::RobotConfig robot = ehc_control::loadRobotConfig(cfg.sim.fake_robot.robot_file);
  const ehc_control::PinholeCamera intrinsics =
      ehc_control::loadPinholeCamera(ehc_sim::simCameraFile(cfg.sim, robot));
  const ehc_sim::SimWorld world(cfg.sim, robot, cfg.scene);
  const Eigen::Isometry3d T_object = world.objectPose(0);
  const Eigen::Vector3d centre = T_object.translation();
  const ehc_perception::PointList surface = trueSurface(shape, width, T_object).points;
  const ehc_perception::GraspGenerator generator(cfg.generator);
  PerceptionOutcome out;
  for (const View& v : kViews) {
    const double el = v.elevation_deg * M_PI / 180.0, az = v.azimuth_deg * M_PI / 180.0;
    const Eigen::Vector3d eye =
        centre + v.distance * Eigen::Vector3d(-std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    const Eigen::Isometry3d T_world_cam = ehc_perception::test::lookAt(eye, centre);
    for (unsigned seed : {11u, 12u}) {
      ehc_sim::SimulatedCamera camera(intrinsics, cfg.sim.camera, seed);
      std::vector<Eigen::Vector3f> cam_points;
      camera.cloud(world, T_world_cam, &cam_points);
      const ehc_perception::PointList points = ehc_perception::transformPoints(cam_points, T_world_cam);
      const ehc_perception::GraspResult res = ehc_perception::generateForTarget(
          generator, points, eye, &centre, cfg.targeting);
      ++out.clouds;
      bool spans = false;
      double best_w = 0.0;
      int best_seen = 0;
      for (const auto& g : res.grasps) {
        spans = spans || spansObject(g, cfg.generator.gripper, surface);
        if (g.width > best_w) best_seen = g.seen_contacts;
        best_w = std::max(best_w, g.width);
      }
      out.spanning += spans;
      out.with_grasps += !res.grasps.empty();
      out.too_wide += res.reason.find("too wide") != std::string::npos;
      if (out.first_reason.empty() && res.grasps.empty()) out.first_reason = res.reason;
      std::printf("%s %.3f m, view (%.2f m, %.0f deg up, %.0f deg), seed %u: %zu grasps, spanning %d, widest %.4f m "
                  "(%d contacts seen); %s\n",
                  toString(shape).c_str(), width, v.distance, v.elevation_deg, v.azimuth_deg, seed,
                  res.grasps.size(), spans, best_w, best_seen, res.reason.c_str());
    }
  }
  return out;
}

}  // namespace

namespace {
/// Runs the Exp-3 downward grasp of `shape` `width` through the in-process pipeline (Bullet);
/// true if the sequencer reports success from a generator candidate and the object rose.
bool graspAndLift(Shape shape, double width, unsigned seed, std::string* what) {
  const GraspPipelineConfig cfg = widthConfig(shape, width, seed);
  GraspPipeline pipe(cfg, seed);
  const double z0 = pipe.world().objectPose(0).translation().z();
  double z_max = z0;
  const double t_end = pipe.time() + 60.0;
  while (!pipe.done() && pipe.time() < t_end) {
    pipe.step();
    z_max = std::max(z_max, pipe.world().objectPose(0).translation().z());
  }
  const auto& results = pipe.sequencer().results();
  if (results.empty()) {
    *what = "no result";
    return false;
  }
  const GraspResult& r = results[0];
  *what = graspResultLine(r) + "; used candidate " + std::to_string(r.used_candidate) + ", rose " +
          std::to_string(z_max - z0) + " m, contact steps " + std::to_string(pipe.counters().collision_steps);
  return r.success && r.used_candidate && z_max - z0 > 0.08;
}
}  // namespace

// Per (shape, width): clouds (of 6) with a grasp whose fingers span the object. Spanning a
// w mm object with the 70 mm opening needs the grasp centred within (70 - w) / 2 mm of the
// object's axis and the width measured at most 69 mm (the margin rule). The sides are measured
// by fitted contact surfaces where the view shows them and by the fitted circle where it does
// not (a cylinder's far side), so objects up to 66 mm (>= 2 mm to spare each side) span in
// every cloud, except: the standing 66 mm cylinder from the 0.6 m / 60 deg view (seed 12),
// whose mantle shows there as an arc of about 90 deg in 32 points (80 x 60 rays): its circle's
// centre is 2 mm off (5 of 6). At 68 mm (1 mm each side) the circles' precision decides: the
// standing cylinder from the 0.6 m / 60 deg view is measured 69.1-69.5 mm (refused, "too
// wide": its diameter from that arc is known to about +-1.5 mm) and the lying one from the
// 0.45 m / 30 deg view is centred more than 1 mm off (4 of 6 each). Boxes span up to 66 mm in
// every cloud: their faces' fits are exact to the noise, the unseen far face is bounded by the
// top face's last samples. At 68 mm the 0.6 m / 60 deg view (seed 12), where the view fits
// neither side (0 contacts seen), is measured 68.6 mm by the grasps of the range-aware
// segmentation's cluster and spans with none of them (67.7 mm and one spanning with the fixed
// 1.5 cm clustering): 5 of 6.
struct WidthCase {
  Shape shape;
  double width;
  int min_spanning;  ///< of 6 clouds
};

std::string caseName(const ::testing::TestParamInfo<WidthCase>& i) {
  return toString(i.param.shape) + "_" + std::to_string(static_cast<int>(std::lround(i.param.width * 1000))) + "mm";
}

const WidthCase kWithinOpening[] = {
    {Shape::Box, 0.060, 6},          {Shape::Box, 0.064, 6},          {Shape::Box, 0.066, 6},
    {Shape::Box, 0.068, 5},          {Shape::StandingCylinder, 0.060, 6}, {Shape::StandingCylinder, 0.064, 6},
    {Shape::StandingCylinder, 0.066, 5}, {Shape::StandingCylinder, 0.068, 4}, {Shape::LyingCylinder, 0.060, 6},
    {Shape::LyingCylinder, 0.064, 6}, {Shape::LyingCylinder, 0.066, 6}, {Shape::LyingCylinder, 0.068, 4}};

class NearLimitWidths : public ::testing::TestWithParam<WidthCase> {};

TEST_P(NearLimitWidths, SingleViewCloudsGiveCollisionFreeGraspsWhoseFingersSpanTheObject) {
  const WidthCase c = GetParam();
  const PerceptionOutcome o = perceive(c.shape, c.width);
  RecordProperty("spanning", std::to_string(o.spanning) + "/" + std::to_string(o.clouds));
  EXPECT_GE(o.spanning, c.min_spanning) << toString(c.shape) << " " << c.width << " m; " << o.first_reason;
  // Only the clouds the count leaves out may be refused as too wide (measured over 69 mm).
  EXPECT_LE(o.too_wide, o.clouds - c.min_spanning) << o.first_reason;
}

TEST_P(NearLimitWidths, TheGeneratorsGraspLiftsTheObjectInBullet) {
  const WidthCase c = GetParam();
  std::string what;
  const bool lifted = graspAndLift(c.shape, c.width, 3, &what);
  std::printf("%s %.3f m: %s\n", toString(c.shape).c_str(), c.width, what.c_str());
  EXPECT_TRUE(lifted) << what;
}

// The grasp starts from the tag (WAIT_TARGET until it is detected): from the start pose the
// hand camera (upright, ready pose) sees the whole tag, its white border included, inside the
// image, and the detector (with its world prior) finds it with the true orientation. From 0.9 m
// (the former start) the lying cylinder's cap tag was cut by the image's bottom edge.
TEST_P(NearLimitWidths, TheStartViewShowsTheWholeTagAndTheDetectorFindsIt) {
  const WidthCase c = GetParam();
  const GraspPipelineConfig cfg = widthConfig(c.shape, c.width, 3);
  const ehc_control::RobotConfig robot = ehc_control::loadRobotConfig(cfg.sim.fake_robot.robot_file);
  const ehc_control::PinholeCamera intrinsics =
      ehc_control::loadPinholeCamera(ehc_sim::simCameraFile(cfg.sim, robot));
  const ehc_sim::SimWorld world(cfg.sim, robot, cfg.scene);
  const Eigen::Isometry3d T_world_cam = world.cameraPose();
  const int body = world.objectBodyIndex(0);
  const Eigen::Isometry3d T_cam_tag = T_world_cam.inverse() * world.tagPose(body);
  // The pattern's outer corners: the black square (kTagSize) and its one-cell white border.
  const double a = 0.5 * kTagSize * 10.0 / 8.0;
  double top = 1e9, bottom = -1e9;
  for (double sx : {-a, a})
    for (double sy : {-a, a}) {
      Eigen::Vector2d uv;
      EXPECT_TRUE(intrinsics.projectsInside(T_cam_tag * Eigen::Vector3d(sx, sy, 0.0), &uv))
          << "a corner of the tag's white border is outside the start image at " << uv.transpose();
      top = std::min(top, uv.y());
      bottom = std::max(bottom, uv.y());
    }
  ehc_sim::SimulatedCamera camera(intrinsics, cfg.sim.camera, 3);
  camera.setScene(world.bodies(), cfg.scene.floor_shade);
  vpImage<unsigned char> image;
  camera.render(world, &image);
  ehc_perception::TagDetector detector(cfg.detector, intrinsics);
  const std::vector<ehc_perception::TagDetection> dets = detector.detect(image, T_world_cam);
  ASSERT_EQ(dets.size(), 1u) << "tag rows " << top << " .. " << bottom << " of " << intrinsics.height;
  EXPECT_EQ(dets[0].id, kTagId);
  const double error_deg =
      Eigen::AngleAxisd(dets[0].T_cam_tag.linear().transpose() * T_cam_tag.linear()).angle() * 180.0 / M_PI;
  std::printf("%s %.3f m: start view, tag rows %.1f .. %.1f of %d, %.1f deg / %.1f mm off\n",
              toString(c.shape).c_str(), c.width, top, bottom, intrinsics.height, error_deg,
              1000.0 * (dets[0].T_cam_tag.translation() - T_cam_tag.translation()).norm());
  EXPECT_LT(error_deg, 10.0);
}

INSTANTIATE_TEST_SUITE_P(WithinTheOpening, NearLimitWidths, ::testing::ValuesIn(kWithinOpening), caseName);

class HeldBackWidth : public ::testing::TestWithParam<WidthCase> {};

TEST_P(HeldBackWidth, IsTooWideWithTheMeasuredWidthAndTheOpeningInTheReason) {
  // 72 mm (held back): no grasp, and the reason names the measured width and the opening (the
  // margin rule: measured width + 2 x clearance <= max_width), from every view of the cylinders
  // (their far side completed by the fitted circle). The box's far face is unseen from every
  // view and bounded by the top face's last samples, short of it by up to one ray spacing along
  // the top face (7.8 mm / sin 30 deg = 16 mm from the 0.45 m / 30 deg view); its near face is
  // fitted (its mean, not its noisy extreme points). From that view both noise seeds measure it
  // 67-69 mm: the view cannot tell it from the 68 mm box, which it must grasp (above), and the
  // grasps it gets there rank as one seen contact and do not span it. `min_spanning` here: the
  // clouds that may have grasps.
  const WidthCase c = GetParam();
  const PerceptionOutcome o = perceive(c.shape, c.width);
  EXPECT_LE(o.with_grasps, c.min_spanning) << o.first_reason;
  EXPECT_EQ(o.spanning, 0) << o.first_reason;
  EXPECT_EQ(o.too_wide + o.with_grasps, o.clouds) << o.first_reason;
  EXPECT_NE(o.first_reason.find("too wide: the object measures 0.07"), std::string::npos) << o.first_reason;
  EXPECT_NE(o.first_reason.find("the gripper opens 0.07 m"), std::string::npos) << o.first_reason;
}

INSTANTIATE_TEST_SUITE_P(BeyondTheOpening, HeldBackWidth,
                         ::testing::Values(WidthCase{Shape::Box, 0.072, 2}, WidthCase{Shape::StandingCylinder, 0.072, 0},
                                           WidthCase{Shape::LyingCylinder, 0.072, 0}),
                         caseName);
