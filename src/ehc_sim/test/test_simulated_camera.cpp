// SimulatedCamera: the rendered tag is found by the project's TagDetector (ehc_perception, ViSP's
// AprilTag detector, the camera pose as its prior for ambiguous poses) with a pose error
// < 1 cm / 2 deg against ground truth; in the ready pose the camera sees the tagged object of
// single_object.yaml; the depth cloud of the table top lies at the table height within noise;
// images are reproducible per seed.

#include "ehc_sim/sim_world.h"
#include "ehc_sim/simulated_camera.h"

#include <gtest/gtest.h>

#include "ehc_common/config_node.h"
#include "ehc_control/pose_math.h"
#include "ehc_test/errors.h"
#include "ehc_perception/tag_detector.h"

// The perception tests' helpers (lookAt).
#include "ehc_test/perception_fixtures.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

using namespace ehc_sim;

namespace {
const std::string kConfig = std::string(EHC_CONFIG_DIR);

struct Rig {
  SimConfig cfg;
  std::unique_ptr<SimWorld> world;
  std::unique_ptr<SimulatedCamera> camera;
  explicit Rig(const std::string& scene, bool noise = true) {
    cfg = loadSimConfig(EHC_SIM_CONFIG);
    if (!noise) {
      cfg.camera.image_noise = 0.0;
      cfg.camera.depth_noise.model = DepthNoiseModel::Gaussian;
      cfg.camera.depth_noise.base = cfg.camera.depth_noise.quadratic = 0.0;
    }
    const ehc_control::RobotConfig robot = ehc_control::loadRobotConfig(cfg.fake_robot.robot_file);
    world = std::make_unique<SimWorld>(cfg, robot, loadSceneConfig(kConfig + "/scenes/" + scene));
    camera = std::make_unique<SimulatedCamera>(ehc_control::loadPinholeCamera(simCameraFile(cfg, robot)), cfg.camera, 1);
    camera->setScene(world->bodies(), world->scene().floor_shade);
    for (int i = 0; i < 5; ++i) world->step(Eigen::VectorXd::Zero(world->robot().nDof()));
  }
};

/// The project's tag detector (ehc_perception), with the camera's pose in the world as the
/// prior for ambiguous tag poses, as ehc_tag_node and the in-process pipeline run it.
std::vector<ehc_perception::TagDetection> detect(const vpImage<unsigned char>& I,
                                                 const ehc_control::PinholeCamera& k,
                                                 double tag_size, const Eigen::Isometry3d& T_world_cam) {
  ehc_perception::TagDetectorConfig cfg;
  cfg.default_tag_size = tag_size;
  ehc_perception::TagDetector detector(cfg, k);
  return detector.detect(I, T_world_cam);
}

/// Pose error of the detected tag against ground truth: (m, deg).
std::pair<double, double> poseError(const ehc_perception::TagDetection& d, const Eigen::Isometry3d& truth) {
  const Eigen::Isometry3d E = truth.inverse() * d.T_cam_tag;
  return {E.translation().norm(), Eigen::AngleAxisd(E.linear()).angle() * 180.0 / M_PI};
}
}  // namespace

TEST(TagTexture, IsTheTag36h11PatternWithItsWhiteBorder) {
  const vpImage<unsigned char> t = makeTagTexture(0, 4);
  ASSERT_EQ(t.getWidth(), 40u);
  ASSERT_EQ(t.getHeight(), 40u);
  for (unsigned i = 0; i < 40; ++i) {
    EXPECT_EQ(t[0][i], 255);   // white outer border
    EXPECT_EQ(t[i][39], 255);
    EXPECT_EQ(t[4][4 + i % 32], 0);  // black square border (cells 1..8)
    EXPECT_EQ(t[4 + i % 32][35], 0);
  }
  EXPECT_THROW(makeTagTexture(587, 4), std::invalid_argument);
  EXPECT_THROW(makeTagTexture(-1, 4), std::invalid_argument);
}

TEST(SimulatedCamera, ReadyPoseSeesTheTaggedObjectOfSingleObjectScene) {
  Rig rig("single_object.yaml");
  // The object's centre projects inside the image with positive depth.
  const Eigen::Isometry3d T_cam = rig.world->cameraPose();
  const Eigen::Vector3d p = T_cam.inverse() * rig.world->objectPose(0).translation();
  ASSERT_GT(p.z(), 0.3);
  const auto& k = rig.camera->intrinsics();
  const double u = k.fx * p.x() / p.z() + k.cx, v = k.fy * p.y() / p.z() + k.cy;
  EXPECT_GT(u, 0.2 * k.width);
  EXPECT_LT(u, 0.8 * k.width);
  EXPECT_GT(v, 0.2 * k.height);
  EXPECT_LT(v, 0.8 * k.height);
  // The detector finds tag 0 from the ready pose (about 1.1 m away).
  vpImage<unsigned char> I;
  rig.camera->render(*rig.world, &I);
  const auto dets = detect(I, k, rig.world->scene().objects[0].tag.size, rig.world->cameraPose());
  ASSERT_EQ(dets.size(), 1u);
  EXPECT_EQ(dets[0].id, 0);
  const Eigen::Isometry3d truth = T_cam.inverse() * rig.world->tagPose(rig.world->objectBodyIndex(0));
  const auto [et, er] = poseError(dets[0], truth);
  EXPECT_LT(et, 0.03) << "at 1.1 m the tag spans ~25 px";
  EXPECT_LT(er, 6.0);
}

TEST(SimulatedCamera, DetectedTagPoseMatchesGroundTruth) {
  Rig rig("single_object.yaml");
  const auto& k = rig.camera->intrinsics();
  const int tag_body = rig.world->objectBodyIndex(0);
  // Views from 0.3 .. 0.8 m, straight on and from the side, wrist tilted up and down.
  int checked = 0;
  for (double x : {0.3, 0.45, 0.6, 0.75})
    for (double yaw : {-0.12, 0.1})
      for (double dq5 : {-0.4, 0.0, 0.4}) {
        Eigen::VectorXd q = rig.world->model().config().arm_ready;
        q[4] += dq5;
        rig.world->setRobotState(Eigen::Vector3d(x, 0.0, yaw), q);
        const Eigen::Isometry3d truth = rig.world->cameraPose().inverse() * rig.world->tagPose(tag_body);
        const Eigen::Vector3d c = truth.translation();
        const double u = k.fx * c.x() / c.z() + k.cx, v = k.fy * c.y() / c.z() + k.cy;
        if (c.z() < 0.3 || c.norm() > 0.8 || u < 0.15 * k.width || u > 0.85 * k.width ||
            v < 0.15 * k.height || v > 0.85 * k.height)
          continue;  // tag not well inside this view
        vpImage<unsigned char> I;
        rig.camera->render(*rig.world, &I);
        const auto dets = detect(I, k, rig.world->scene().objects[0].tag.size, rig.world->cameraPose());
        SCOPED_TRACE("base x " + std::to_string(x) + " yaw " + std::to_string(yaw) + " dq5 " +
                     std::to_string(dq5) + ", distance " + std::to_string(c.norm()) + " m");
        ASSERT_EQ(dets.size(), 1u);
        EXPECT_EQ(dets[0].id, 0);
        const auto [et, er] = poseError(dets[0], truth);
        EXPECT_LT(et, 0.01);
        EXPECT_LT(er, 2.0);
        ++checked;
      }
  EXPECT_GE(checked, 6) << "too few views with the tag in the image";
}

TEST(SimulatedCamera, TagOnACylinderIsDetectedCloseUp) {
  // table_three_objects.yaml's middle object is a cylinder with its tag on -x. Close up (the
  // grasp sequencer looks from 0.4 m back, hand level, camera above the TCP) the tag must be
  // drawn whole: a cylinder edge through the tag once drew a seam across it and the detector
  // lost it.
  Rig rig("table_three_objects.yaml");
  const auto& k = rig.camera->intrinsics();
  ASSERT_EQ(rig.world->scene().objects[1].shape, ShapeType::Cylinder);
  const int tag_body = rig.world->objectBodyIndex(1);
  const Eigen::Vector3d centre = rig.world->bodyPose(tag_body).translation();
  int checked = 0;
  for (double back : {0.30, 0.40, 0.50})
    for (double side : {-0.03, 0.0, 0.03}) {
      Eigen::Isometry3d tcp = Eigen::Isometry3d::Identity();  // z forward (+x), x up: level hand
      tcp.linear() << 0, 0, 1, 0, -1, 0, 1, 0, 0;
      tcp.translation() = centre + Eigen::Vector3d(-back, side, -0.05);
      Eigen::Vector3d base;
      Eigen::VectorXd q;
      ASSERT_TRUE(rig.world->model().inverseKinematics(tcp, 7, 20, &base, &q)) << back << " " << side;
      rig.world->setRobotState(base, q);
      const Eigen::Isometry3d truth = rig.world->cameraPose().inverse() * rig.world->tagPose(tag_body);
      const Eigen::Vector3d c = truth.translation();
      const double u = k.fx * c.x() / c.z() + k.cx, v = k.fy * c.y() / c.z() + k.cy;
      SCOPED_TRACE("TCP " + std::to_string(back) + " m back, " + std::to_string(side) + " m aside; tag at " +
                   std::to_string(c.norm()) + " m, pixel (" + std::to_string(u) + ", " + std::to_string(v) + ")");
      ASSERT_TRUE(c.z() > 0.2 && u > 0.1 * k.width && u < 0.9 * k.width && v > 0.1 * k.height && v < 0.9 * k.height);
      vpImage<unsigned char> I;
      rig.camera->render(*rig.world, &I);
      bool found = false;
      for (const auto& d : detect(I, k, rig.world->scene().objects[1].tag.size, rig.world->cameraPose()))
        if (d.id == rig.world->scene().objects[1].tag.id) {
          found = true;
          const auto [et, er] = poseError(d, truth);
          EXPECT_LT(et, 0.01);
          // Head-on, a 3 cm tag's rotation is poorly conditioned (4-12 deg measured here).
          EXPECT_LT(er, 15.0);
        }
      EXPECT_TRUE(found);
      ++checked;
    }
  EXPECT_EQ(checked, 9);
}

TEST(SimulatedCamera, AllThreeObjectsAreDetectedOnTheTable) {
  Rig rig("table_three_objects.yaml");
  rig.world->setRobotState(Eigen::Vector3d(0.6, 0.0, 0.0), rig.world->model().config().arm_ready);
  vpImage<unsigned char> I;
  rig.camera->render(*rig.world, &I);
  std::vector<int> ids;
  for (const auto& d : detect(I, rig.camera->intrinsics(), 0.04, rig.world->cameraPose())) ids.push_back(d.id);
  std::sort(ids.begin(), ids.end());
  EXPECT_EQ(ids, (std::vector<int>{1, 2, 3}));
}

TEST(SimulatedCamera, TableTopCloudLiesAtTheTableHeight) {
  Rig rig("table_three_objects.yaml");
  const double height = rig.world->scene().tables[0].height;
  const Eigen::Isometry3d T_cam = rig.world->cameraPose();
  std::vector<Eigen::Vector3f> pts;
  rig.camera->cloud(*rig.world, &pts);
  ASSERT_GT(pts.size(), 1000u);
  int on_top = 0;
  double sum = 0, worst = 0;
  for (const auto& pc : pts) {
    const Eigen::Vector3d p = T_cam * pc.cast<double>();
    bool near_object = false;
    for (const auto& o : rig.world->scene().objects)
      near_object |= (p.head<2>() - o.position.head<2>()).norm() < 0.08;
    if (near_object || p.x() < 1.6 || p.x() > 2.25 || std::abs(p.y()) > 0.5 || p.z() < 0.5) continue;
    const double z = (T_cam.inverse() * p).z();  // depth along the optical axis
    const double sigma = rig.cfg.camera.depth_noise.sigma(z);
    // Noise is along the ray: the height error is at most the depth error.
    if (std::abs(p.z() - height) / sigma > worst) {
      worst = std::abs(p.z() - height) / sigma;
      if (worst > 5.0) ADD_FAILURE() << "point " << p.transpose() << " depth " << z;
    }
    sum += p.z() - height;
    ++on_top;
  }
  ASSERT_GT(on_top, 300);
  EXPECT_LT(worst, 5.0) << "every table point within 5 sigma of the depth noise";
  EXPECT_NEAR(sum / on_top, 0.0, 0.002) << "mean height error";
  // Without noise: exact (the rasterised depth is the ray's intersection with the plane).
  Rig exact("table_three_objects.yaml", false);
  exact.camera->cloud(*exact.world, &pts);
  const Eigen::Isometry3d T = exact.world->cameraPose();
  int n = 0;
  for (const auto& pc : pts) {
    const Eigen::Vector3d p = T * pc.cast<double>();
    bool near_object = false;
    for (const auto& o : exact.world->scene().objects)
      near_object |= (p.head<2>() - o.position.head<2>()).norm() < 0.08;
    if (near_object || p.x() < 1.6 || p.x() > 2.25 || std::abs(p.y()) > 0.5 || p.z() < 0.5) continue;
    EXPECT_NEAR(p.z(), height, 2e-4);
    ++n;
  }
  EXPECT_GT(n, 300);
  // Every point is inside the range limits and in front of the camera.
  for (const auto& pc : pts) {
    EXPECT_GE(pc.z(), exact.cfg.camera.min_range);
    EXPECT_LE(pc.z(), exact.cfg.camera.max_range);
  }
}

TEST(SimulatedCamera, ImagesAreReproduciblePerSeed) {
  Rig rig("single_object.yaml");
  vpImage<unsigned char> a, b, c;
  rig.camera->reseed(5);
  rig.camera->render(*rig.world, &a);
  rig.camera->reseed(5);
  rig.camera->render(*rig.world, &b);
  rig.camera->reseed(6);
  rig.camera->render(*rig.world, &c);
  ASSERT_EQ(a.getSize(), b.getSize());
  EXPECT_TRUE(std::equal(a.bitmap, a.bitmap + a.getSize(), b.bitmap));
  EXPECT_FALSE(std::equal(a.bitmap, a.bitmap + a.getSize(), c.bitmap));
  EXPECT_EQ(a.getWidth(), 640u);
  EXPECT_EQ(a.getHeight(), 480u);
}

TEST(SimulatedCamera, BadConfigurationThrows) {
  SimulatedCameraConfig c;
  c.ray_cols = 1;
  EXPECT_THROW(SimulatedCamera(ehc_control::PinholeCamera(), c, 1), std::invalid_argument);
  ehc_control::PinholeCamera k;
  k.fx = -1;
  EXPECT_THROW(SimulatedCamera(k, SimulatedCameraConfig(), 1), std::invalid_argument);
  // Valid cameras the simulator does not render: tiny images, extreme focal lengths.
  ehc_control::PinholeCamera tiny;
  tiny.width = tiny.height = 8;
  tiny.cx = tiny.cy = 4;
  ASSERT_NO_THROW(tiny.validate());
  EXPECT_THROW(SimulatedCamera(tiny, SimulatedCameraConfig(), 1), std::invalid_argument);
  ehc_control::PinholeCamera wide;
  wide.fx = 0.5;
  ASSERT_NO_THROW(wide.validate());
  EXPECT_THROW(SimulatedCamera(wide, SimulatedCameraConfig(), 1), std::invalid_argument);
}

TEST(SimulatedCamera, CameraInsideOrTouchingAnObjectDoesNotCrash) {
  // Faces with a corner behind the camera used to crash vpImageSimulator: they are skipped.
  Rig rig("single_object.yaml");
  const auto& obj = rig.world->scene().objects[0];
  vpImage<unsigned char> I;
  const Eigen::Isometry3d T_obj = rig.world->objectPose(0);
  for (double d : {0.05, 0.02, 0.005, 0.0, -0.01}) {
    // Camera looking at the object centre from `d` in front of its -x face.
    Eigen::Isometry3d T_cam = Eigen::Isometry3d::Identity();
    T_cam.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;  // optical z along world x
    T_cam.translation() = T_obj.translation() - Eigen::Vector3d(0.5 * obj.size.x() + d, 0, 0);
    std::vector<Eigen::Isometry3d> poses(rig.world->bodies().size());
    for (std::size_t i = 0; i < poses.size(); ++i) poses[i] = rig.world->bodyPose(static_cast<int>(i));
    ASSERT_NO_THROW(rig.camera->render(T_cam, poses, &I));
    EXPECT_EQ(I.getWidth(), 640u);
  }
  EXPECT_GT(rig.camera->clippedFaces(), 0);
}

// The in-process pipeline skips images with no tag in view (GraspPipeline::perceive): tagInView
// may say "in view" for a tag the detector does not find (occluded, too small), never the
// reverse. Random views of the Exp-2 table's three tags, from 0.2 to 1.5 m, from in front and
// behind, looking near the tags so that many are cut by the image border: whenever tagInView is
// false, the project's detector (the demo's configuration, whole image, noisy image as in the
// runs) finds no tag in the rendered image.
TEST(SimulatedCamera, TagInViewIsFalseOnlyWhenTheDetectorFindsNoTag) {
  Rig rig("table_three_objects.yaml");
  std::vector<BodyConfig> untagged = rig.world->bodies();
  for (auto& b : untagged) b.tag.enabled = false;
  SimulatedCamera plain(rig.camera->intrinsics(), rig.camera->config(), 1);
  plain.setScene(untagged, rig.world->scene().floor_shade);
  std::vector<Eigen::Isometry3d> poses(rig.world->bodies().size());
  std::vector<Eigen::Isometry3d> tags;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    poses[i] = rig.world->bodyPose(static_cast<int>(i));
    if (rig.world->bodies()[i].tag.enabled) tags.push_back(rig.world->tagPose(static_cast<int>(i)));
  }
  ASSERT_EQ(tags.size(), 3u);
  const ehc_perception::TagDetectorConfig dcfg = ehc_perception::loadTagDetectorConfig(
      ehc_common::ConfigNode::loadFile(kConfig + "/demo/tag_front.yaml", "test").child("tag_detector"));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0), r01(0.0, 1.0);
  int in_view = 0, found_in_view = 0, cut = 0, behind = 0, checked = 0;
  vpImage<unsigned char> with, without;
  for (int k = 0; k < 240; ++k) {
    const Eigen::Isometry3d& tag = tags[static_cast<std::size_t>(k) % tags.size()];
    // Direction from the tag: mostly in front (its z axis), one view in six from behind.
    Eigen::Vector3d dir = tag.linear() * Eigen::Vector3d(0.8 * u(rng), 0.8 * u(rng), k % 6 == 5 ? -1.0 : 1.0);
    dir.z() = std::abs(dir.z()) + 0.1;  // from above the table
    const Eigen::Vector3d eye = tag.translation() + (0.2 + 1.3 * r01(rng)) * dir.normalized();
    Eigen::Isometry3d T = ehc_perception::test::lookAt(eye, tag.translation());
    // Turn the camera so that the tag's centre is seen at pixel (u, v): within 30 px of the
    // image border in half of the views (most of them cut the tag), anywhere in the others.
    const ehc_control::PinholeCamera& K = rig.camera->intrinsics();
    double pu = K.width * r01(rng), pv = K.height * r01(rng);
    if (k % 2 == 0) {
      const double edge = 30.0 * u(rng);
      if (k % 4 == 0) pu = (u(rng) < 0 ? 0.0 : K.width) + edge;
      else pv = (u(rng) < 0 ? 0.0 : K.height) + edge;
    }
    const Eigen::Vector3d ray((pu - K.cx) / K.fx, (pv - K.cy) / K.fy, 1.0);
    T.linear() = T.linear() * Eigen::Quaterniond::FromTwoVectors(ray.normalized(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    rig.camera->render(T, poses, &with);
    ehc_perception::TagDetector detector(dcfg, K);
    if (rig.camera->tagInView(T, poses)) {
      ++in_view;
      if (k % 4 == 1) found_in_view += !detector.detect(with, T).empty();  // a sample: how often found
      continue;
    }
    const std::vector<ehc_perception::TagDetection> found = detector.detect(with, T);
    ++checked;
    plain.render(T, poses, &without);
    const bool drawn = !std::equal(with.bitmap, with.bitmap + with.getSize(), without.bitmap);
    behind += k % 6 == 5;
    cut += drawn && k % 6 != 5;
    EXPECT_TRUE(found.empty()) << "view " << k << ": tagInView is false but the detector finds tag " << found[0].id
                               << " (corners " << found[0].corners[0].transpose() << " ...)";
  }
  std::printf("240 views: %d with a tag in view (%d of a sample found), %d not (%d with a tag cut by the border, %d from behind)\n",
              in_view, found_in_view, checked, cut, behind);
  EXPECT_GE(in_view, 40);  // every outcome is exercised
  EXPECT_GE(cut, 40);
  EXPECT_GE(behind, 20);
}

// A skipped image advances the noise stream as a rendered one: the clouds and images after it are
// those of the run that rendered it.
TEST(SimulatedCamera, SkippingAnImageKeepsTheNoiseStream) {
  Rig rig("single_object.yaml");
  SimulatedCamera other(rig.camera->intrinsics(), rig.camera->config(), 9);
  rig.camera->reseed(9);
  other.setScene(rig.world->bodies(), rig.world->scene().floor_shade);
  vpImage<unsigned char> a, b;
  rig.camera->render(*rig.world, &a);
  other.skipImage();
  std::vector<Eigen::Vector3f> pa, pb;
  rig.camera->cloud(*rig.world, &pa);
  other.cloud(*rig.world, &pb);
  ASSERT_EQ(pa.size(), pb.size());
  ASSERT_FALSE(pa.empty());
  EXPECT_TRUE(std::equal(pa.begin(), pa.end(), pb.begin()));
  rig.camera->render(*rig.world, &a);
  other.render(*rig.world, &b);
  EXPECT_TRUE(std::equal(a.bitmap, a.bitmap + a.getSize(), b.bitmap));
  EXPECT_TRUE(rig.camera->tagInView(*rig.world));  // the ready pose sees the tag (test above)
}

namespace {
/// A camera of `rig` with the depth model `noise` (seeded).
SimulatedCamera depthCamera(const Rig& rig, const DepthNoiseConfig& noise, unsigned seed, double max_range = 6.0) {
  SimulatedCameraConfig c = rig.camera->config();
  c.depth_noise = noise;
  c.max_range = max_range;
  return SimulatedCamera(rig.camera->intrinsics(), c, seed);
}

/// Looking straight down from `height` over the empty floor behind the robot.
Eigen::Isometry3d downwards(double height) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  T.translation() = Eigen::Vector3d(-3.0, -3.0, height);
  return T;
}

DepthNoiseConfig stereo() {
  DepthNoiseConfig d;
  d.model = DepthNoiseModel::Stereo;
  return d;
}
}  // namespace

// Intel's D400 RMS error, z^2 * subpixel / (focal_px * baseline): a flat floor seen straight down
// (every sample at the same depth, no edge, no grazing angle) from 0.5, 1 and 2 m.
TEST(DepthNoise, StereoModelGrowsWithTheSquareOfTheDistance) {
  Rig rig("single_object.yaml", false);
  const DepthNoiseConfig model = stereo();
  for (double h : {0.5, 1.0, 2.0}) {
    SimulatedCamera cam = depthCamera(rig, model, 4);
    std::vector<Eigen::Vector3f> pts;
    cam.cloud(*rig.world, downwards(h), &pts);
    ASSERT_EQ(pts.size(), 80u * 60u) << "every sample sees the floor, none is dropped";
    double sum = 0.0, sum2 = 0.0;
    for (const auto& p : pts) {
      sum += p.z() - h;
      sum2 += (p.z() - h) * (p.z() - h);
    }
    const double mean = sum / pts.size(), rms = std::sqrt(sum2 / pts.size());
    const double expected = h * h * 0.08 / (447.0 * 0.050);
    std::printf("stereo depth noise at %.1f m: RMS %.2f mm (model %.2f mm), mean %.3f mm\n", h, 1e3 * rms, 1e3 * expected, 1e3 * mean);
    EXPECT_NEAR(model.sigma(h), expected, 1e-12);
    EXPECT_NEAR(rms, expected, 0.05 * expected);
    EXPECT_LT(std::abs(mean), 0.1 * expected);
  }
  // The former model stays available: sigma = base + quadratic z^2.
  DepthNoiseConfig gaussian;
  SimulatedCamera cam = depthCamera(rig, gaussian, 4);
  std::vector<Eigen::Vector3f> pts;
  cam.cloud(*rig.world, downwards(1.0), &pts);
  double sum2 = 0.0;
  for (const auto& p : pts) sum2 += (p.z() - 1.0) * (p.z() - 1.0);
  EXPECT_NEAR(std::sqrt(sum2 / pts.size()), 0.003, 0.00015);
}

// Flying pixels: with no Gaussian part and no holes, the only differences from the exact depth
// are samples next to a depth edge, each between its own surface and a neighbour's.
TEST(DepthNoise, FlyingPixelsLieBetweenTheSurfacesOfADepthEdge) {
  Rig rig("table_three_objects.yaml", false);
  rig.world->setRobotState(Eigen::Vector3d(0.9, 0.0, 0.0), rig.world->model().config().arm_ready);
  DepthNoiseConfig flying = stereo();
  flying.subpixel = 0.0;
  flying.grazing_angle = 90.0;
  flying.flying_pixels = 1.0;
  // Every surface in range, so that each sample's neighbours are in the exact cloud.
  SimulatedCamera exact_cam = depthCamera(rig, DepthNoiseConfig{DepthNoiseModel::Gaussian, 0.0, 0.0}, 1, 100.0);
  SimulatedCamera flying_cam = depthCamera(rig, flying, 1, 100.0);
  std::vector<Eigen::Vector3f> exact, noisy;
  exact_cam.cloud(*rig.world, &exact);
  flying_cam.cloud(*rig.world, &noisy);
  ASSERT_EQ(exact.size(), noisy.size());
  // The exact depth per grid cell, to look at a sample's neighbours.
  const ehc_control::PinholeCamera& K = rig.camera->intrinsics();
  const int cols = rig.camera->config().ray_cols, rows = rig.camera->config().ray_rows;
  std::vector<double> grid(static_cast<std::size_t>(cols * rows), -1.0);
  auto cell = [&](const Eigen::Vector3f& p) {
    const double u = K.fx * p.x() / p.z() + K.cx, v = K.fy * p.y() / p.z() + K.cy;
    return std::make_pair(static_cast<int>(std::lround((u + 0.5) * cols / K.width - 0.5)),
                          static_cast<int>(std::lround((v + 0.5) * rows / K.height - 0.5)));
  };
  for (const auto& p : exact) {
    const auto [c, r] = cell(p);
    grid[static_cast<std::size_t>(r * cols + c)] = p.z();
  }
  int moved = 0, checked = 0;
  for (std::size_t i = 0; i < exact.size(); ++i) {
    if (std::abs(noisy[i].z() - exact[i].z()) < 1e-6) continue;
    ++moved;
    const auto [c, r] = cell(exact[i]);
    double lo = exact[i].z(), hi = exact[i].z(), jump = 0.0;
    bool known = true;  // a neighbour beyond max_range (the floor near the horizon) is not in the cloud
    const int dc[4] = {1, -1, 0, 0}, dr[4] = {0, 0, 1, -1};
    for (int k = 0; k < 4; ++k) {
      const int cc = c + dc[k], rr = r + dr[k];
      if (cc < 0 || rr < 0 || cc >= cols || rr >= rows) continue;
      const double zn = grid[static_cast<std::size_t>(rr * cols + cc)];
      known = known && zn >= 0;
      if (zn < 0) continue;
      lo = std::min(lo, zn);
      hi = std::max(hi, zn);
      jump = std::max(jump, std::abs(zn - exact[i].z()));
    }
    if (!known) continue;
    ++checked;
    EXPECT_GT(jump, 0.5 * flying.edge_jump) << "sample " << i << " moved without a depth edge";
    EXPECT_GE(noisy[i].z(), lo - 1e-6);
    EXPECT_LE(noisy[i].z(), hi + 1e-6);
  }
  std::printf("%d of %zu samples are flying pixels (%d checked against their neighbours)\n", moved, exact.size(), checked);
  EXPECT_GT(checked, 30) << "the table edge and the objects' silhouettes give edges";
  EXPECT_LT(moved, static_cast<int>(exact.size()) / 5) << "only edges: slanted planes (the floor, the table) have none";
}

// Holes: the floor seen at a low angle loses samples with a probability rising from 0 at
// grazing_angle to 1 at 90 deg; nearer to the normal nothing is lost.
TEST(DepthNoise, HolesAtGrazingAngles) {
  Rig rig("single_object.yaml", false);
  DepthNoiseConfig holes = stereo();
  holes.subpixel = 0.0;
  holes.flying_pixels = 0.0;
  Eigen::Isometry3d T = ehc_control::lookAt(Eigen::Vector3d(-3.0, -3.0, 0.4), Eigen::Vector3d(-1.0, -3.0, 0.0));
  SimulatedCamera exact_cam = depthCamera(rig, DepthNoiseConfig{DepthNoiseModel::Gaussian, 0.0, 0.0}, 2);
  std::vector<Eigen::Vector3f> exact;
  exact_cam.cloud(*rig.world, T, &exact);
  double expected_lost = 0.0, var = 0.0;
  for (const auto& p : exact) {
    const Eigen::Vector3d ray = T.linear() * p.cast<double>().normalized();
    const double angle = std::acos(std::abs(ray.z())) * 180.0 / M_PI;  // floor normal: world z
    const double q = std::clamp((angle - holes.grazing_angle) / (90.0 - holes.grazing_angle), 0.0, 1.0);
    expected_lost += q;
    var += q * (1 - q);
  }
  std::vector<Eigen::Vector3f> a, b, c;
  depthCamera(rig, holes, 2).cloud(*rig.world, T, &a);
  depthCamera(rig, holes, 2).cloud(*rig.world, T, &b);
  depthCamera(rig, holes, 3).cloud(*rig.world, T, &c);
  const double lost = static_cast<double>(exact.size() - a.size());
  std::printf("grazing floor: %zu samples, %.0f lost (expected %.1f)\n", exact.size(), lost, expected_lost);
  ASSERT_GT(expected_lost, 100.0) << "the view must graze the floor";
  EXPECT_NEAR(lost, expected_lost, 4.0 * std::sqrt(var) + 1.0);
  EXPECT_TRUE(a == b) << "same seed, same cloud";
  EXPECT_FALSE(a == c) << "another seed, other holes";
}

TEST(DepthNoise, BadSettingsAreRejectedNamingTheField) {
  const auto err = [](const std::string& yaml) {
    return ehc_test::errorOf([&] {
      const auto n = ehc_common::ConfigNode::loadString(yaml, "cam.yaml", "T");
      loadSimulatedCameraConfig(n);
      n.rejectUnknownKeys();
    });
  };
  EXPECT_NE(err("depth_noise: {model: tof}\n").find("depth_noise.model"), std::string::npos);
  EXPECT_NE(err("depth_noise: {model: stereo, subpixel: -1}\n").find("sim.camera.depth_noise.subpixel"), std::string::npos);
  EXPECT_NE(err("depth_noise: {flying_pixels: 1.5}\n").find("flying_pixels"), std::string::npos);
  EXPECT_NE(err("depth_noise: {grazing_angle: .nan}\n").find("grazing_angle"), std::string::npos);
  EXPECT_NE(err("depth_noise: {basline: 0.05}\n").find("basline"), std::string::npos) << "unknown key";
}
