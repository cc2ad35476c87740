// Benchmarks of the perception core (DESIGN.md section 11), one JSON object per line:
//  - perception.tag_detect_pose_640x480: AprilTag 36h11 detection + pose, rendered image;
//    _noisy: a stream with the simulator's pixel noise, _noisy_tracked: with the tracking window
//  - perception.grasps_object_20k: grasp generation on a 20 000-point noisy object cloud
//  - perception.grasps_scene: table scene (RANSAC plane + clusters + grasps on one object)
//  - perception.obstacle_distances_2cm: every robot link vs a 2 cm OctoMap of a table scene
//  - perception.octomap_insert_cloud: ray insertion of a 20 000-point depth cloud
//  - perception.obstacle_monitor_bound_d435 / _insert_d435: ObstacleMonitor bounding (voxel +
//    budget) and inserting a full 640x480 D435 frame (307 200 points, wall 1.5 m ahead)
//  - perception.obstacle_cloud_300k / _2M and perception.grasp_cloud_300k / _2M: the work of
//    ehc_obstacle_node and ehc_grasp_node per cloud, from the message's bytes (an organised
//    640x480 or 1920x1080 depth frame of a table with a box, 0.6 m away): the point budget read
//    (PointBudget), the transform, then ObstacleMonitor::queueCloud (the node's callback; the
//    ray casting follows, points_per_update per publish cycle) or generateForTarget;
//    perception.grasp_cloud_2M_blob: 2 M points in a 0.2 m cube (one object of every point, the
//    worst case of the generator). ROS's own deserialisation is not included
//    (bench_obstacle_node_rate measures the node).
#include "ehc_common/bench_util.h"
#include "ehc_control/whole_body_model.h"
#include "ehc_control/pinhole_camera.h"
#include "ehc_perception/grasp_generator.h"
#include "ehc_perception/obstacle_distance_field.h"
#include "ehc_perception/obstacle_monitor.h"
#include "ehc_perception/point_cloud_layout.h"
#include "ehc_perception/tag_detector.h"
#include "ehc_perception/tag_image_renderer.h"
#include "ehc_test/perception_fixtures.h"

#include <algorithm>
#include <random>

using namespace ehc_perception;
using namespace ehc_perception::test;

namespace {

PointList resample(const PointList& in, std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, in.size() - 1);
  std::normal_distribution<float> noise(0.f, 0.0015f);
  PointList out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i)
    out.push_back(in[pick(rng)] + Eigen::Vector3f(noise(rng), noise(rng), noise(rng)));
  return out;
}

/// AprilTag detection + pose on rendered images, and on a noisy stream searched whole and tracked.
void benchTags() {
  const ehc_control::PinholeCamera cam = ehc_control::loadPinholeCamera(cameraYaml());
  TagDetectorConfig cfg;
  cfg.default_tag_size = 0.05;
  TagDetector det(cfg, cam);
  TagImageRenderer renderer(cam);
  std::vector<vpImage<unsigned char>> images;
  for (int k = 0; k < 5; ++k)
    images.push_back(renderer.render(
        {{k, 0.05, facingTag(0.03 * k - 0.06, 0.02, 0.45 + 0.05 * k, 0.3, 0.1, 0.2 * k)}}));
  int found = 0;
  ehc_common::benchReport("perception.tag_detect_pose_640x480", 200, [&](int i) {
    const auto d = det.detect(images[static_cast<std::size_t>(i % 5)]);
    found += static_cast<int>(d.size());
  });
  ehc_common::benchPrintValues("perception.tag_detect_pose_640x480.detections", {{"found", found}, {"expected", 200}});
  // A stream: one tag crossing the view 0.6 m away (1 cm, 1 deg a frame) with the simulator's
  // pixel noise (config/sim/bullet_sim.yaml camera.image_noise: 2 grey levels, i.i.d.),
  // searched whole every image, then with the tracking window of config/demo/tag_*.yaml.
  std::mt19937 rng(7);
  std::vector<vpImage<unsigned char>> stream;
  for (int k = 0; k < 20; ++k) {
    stream.push_back(renderer.render(
        {{0, 0.05, facingTag(0.01 * k - 0.1, 0.02, 0.6, 0.2, 0.1, 0.0175 * k)}}));
    addPixelNoise(&stream.back(), &rng);
  }
  for (const int margin : {0, 40}) {
    TagDetectorConfig c = cfg;
    c.roi_margin = margin;
    TagDetector tracker(c, cam);
    const std::string name = margin ? "perception.tag_detect_pose_640x480_noisy_tracked"
                                    : "perception.tag_detect_pose_640x480_noisy";
    int n = 0;
    ehc_common::benchReport(name, 100, [&](int i) {
      n += static_cast<int>(tracker.detect(stream[static_cast<std::size_t>(i % 20)]).size());
    });
    ehc_common::benchPrintValues(name + ".detections", {{"found", n},
                                                        {"expected", 100},
                                                        {"whole_images", tracker.fullFrameSearches()},
                                                        {"windows", tracker.windowSearches()}});
  }
}

/// Grasp generation on 20k-point objects and on a table scene; the grasp counts go to *sink.
void benchGrasps(double* sink) {
  const GraspGenerator gen{GraspGeneratorConfig()};
  Surface box = boxSurface(Eigen::Vector3d(0.05, 0.12, 0.10), 0.002);
  box.transform(pose(0.6, 0.1, 0.05, 0.5));
  Surface cyl = cylinderSurface(0.03, 0.0, 0.12, 0.002, false, true);
  cyl.transform(pose(0.6, -0.1, 0.0, 0.0));
  Surface bottle = bottleSurface(0.028, 0.14, 0.03, 0.013, 0.05, 0.002);
  bottle.transform(pose(0.55, 0.05, 0.03, 0.3, M_PI / 2));
  const std::vector<PointList> objects = {resample(box.points, 20000, 1),
                                          resample(cyl.points, 20000, 2),
                                          resample(bottle.points, 20000, 3)};
  const Eigen::Vector3d view(0, 0, 0.9);
  std::size_t n_grasps = 0;
  ehc_common::benchReport("perception.grasps_object_20k", 30, [&](int i) {
    n_grasps += gen.generate(objects[static_cast<std::size_t>(i % 3)], view).grasps.size();
  }, {{"points", 20000}});
  *sink += static_cast<double>(n_grasps);

  Surface scene = tableSurface(0.7, 0.0, 0.6, 0.8, 0.7, 0.005);
  Surface b2 = boxSurface(Eigen::Vector3d(0.05, 0.12, 0.10), 0.003);
  b2.transform(pose(0.65, 0.15, 0.75, 0.4));
  Surface c2 = cylinderSurface(0.03, 0.0, 0.12, 0.003, false, true);
  c2.transform(pose(0.75, -0.15, 0.7, 0.0));
  scene.append(b2);
  scene.append(c2);
  const PointList scene_cloud = scene.noisy(0.001, 4);
  const Eigen::Vector3d near(0.75, -0.15, 0.76);
  ehc_common::benchReport("perception.grasps_scene", 10, [&](int) {
    *sink += static_cast<double>(gen.generateFromScene(scene_cloud, Eigen::Vector3d(0.2, 0, 1.3), &near).grasps.size());
  }, {{"points", scene_cloud.size()}});
}

/// Obstacle distances on a 2 cm OctoMap, ray insertion, and ObstacleMonitor on a D435 frame.
void benchObstacles() {
  const ehc_control::WholeBodyModel model(ehc_control::loadRobotConfig(robotYaml()));
  ObstacleMapConfig cfg;
  cfg.resolution = 0.02;
  const ehc_control::RobotCollisionModel robot(model.urdfXml(), model.config().arm_joints, model.config().checked_links);
  ObstacleDistanceField field(cfg, robot);
  // Table scene: 0.8 x 1.2 m table top at 0.7 m with legs, two objects, a wall behind.
  field.addOccupiedBox(Eigen::Vector3d(0.9, -0.6, 0.66), Eigen::Vector3d(1.7, 0.6, 0.70));
  for (double x : {0.92, 1.66})
    for (double y : {-0.58, 0.56})
      field.addOccupiedBox(Eigen::Vector3d(x, y, 0.04), Eigen::Vector3d(x + 0.02, y + 0.02, 0.66));
  field.addOccupiedBox(Eigen::Vector3d(1.0, -0.1, 0.70), Eigen::Vector3d(1.06, 0.02, 0.80));
  field.addOccupiedBox(Eigen::Vector3d(1.1, 0.2, 0.70), Eigen::Vector3d(1.16, 0.26, 0.82));
  field.addOccupiedBox(Eigen::Vector3d(2.0, -1.0, 0.04), Eigen::Vector3d(2.04, 1.0, 1.5));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<std::vector<Eigen::Isometry3d>> poses;
  for (int k = 0; k < 50; ++k) {
    Eigen::VectorXd q = model.config().arm_ready;
    for (int j = 0; j < q.size(); ++j) q[j] += 0.4 * u(rng);
    const Eigen::Vector3d base(0.35 + 0.1 * u(rng), 0.1 * u(rng), 0.2 * u(rng));
    poses.push_back(field.linkPoses(model, base, q));
  }
  std::size_t pairs = 0;
  ehc_common::benchReport("perception.obstacle_distances_2cm", 2000, [&](int i) {
    pairs += field.distances(poses[static_cast<std::size_t>(i % 50)]).size();
  }, {{"links", robot.links().size()}, {"occupied_voxels", field.occupiedLeafCount()}});
  ehc_common::benchPrintValues("perception.obstacle_distances_2cm.pairs_per_cycle",
                               {{"mean", ehc_common::jsonNumber(static_cast<double>(pairs) / 2000.0)}});

  // Depth cloud of a wall + table seen from 1 m: ray insertion cost.
  PointList cloud;
  for (int i = 0; i < 20000; ++i)
    cloud.push_back(Eigen::Vector3f(1.5f, static_cast<float>(0.8 * u(rng)),
                                    static_cast<float>(0.2 + 1.0 * (u(rng) + 1) / 2)));
  ObstacleDistanceField field2(cfg, robot);
  ehc_common::benchReport("perception.octomap_insert_cloud", 20, [&](int) {
    field2.insertCloud(cloud, Eigen::Vector3d(0.3, 0.0, 1.2));
  }, {{"points", 20000}, {"range_m", 1.3}});

  // A full D435 frame through ObstacleMonitor (the node's path): bounded, then inserted.
  const PointList frame = fullD435Wall();
  ObstacleMonitor monitor(model.config(), cfg, ObstacleMonitorParams());
  std::size_t kept = 0;
  ehc_common::benchReport("perception.obstacle_monitor_bound_d435", 20, [&](int) {
    kept = monitor.boundCloud(frame).size();
  }, {{"points", 307200}});
  ehc_common::benchReport("perception.obstacle_monitor_insert_d435", 20, [&](int) {
    monitor.insertCloud(0.0, frame, Eigen::Vector3d(0.0, 0.0, 1.0));
  }, {{"points", 307200}, {"inserted", kept}});
}

/// The nodes' work per cloud, from the message's bytes, at 300 k and 2 M points (see the top).
void benchCloudPaths(double* sink) {
  const ehc_control::RobotConfig robot = ehc_control::loadRobotConfig(robotYaml());
  const Box table{pose(1.0, 0.0, 0.685, 0.0), Eigen::Vector3d(0.8, 1.2, 0.03)};
  const Box box{pose(0.95, 0.05, 0.75, 0.4), Eigen::Vector3d(0.05, 0.06, 0.10)};
  const Eigen::Vector3d centre = box.pose.translation();
  const Eigen::Isometry3d cam = lookAt(centre + Eigen::Vector3d(-0.42, 0.0, 0.42), centre);
  const GraspGenerator gen{GraspGeneratorConfig()};
  const GraspTargetingParams targeting;
  const ObstacleMonitorParams obstacle;
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> blob(0.0f, 0.2f);
  PointList cube;
  for (int i = 0; i < 2000000; ++i) cube.emplace_back(0.85f + blob(rng), blob(rng), 0.7f + blob(rng));
  struct Case {
    std::string name;
    PackedCloud msg;
  };
  std::vector<Case> cases;
  cases.push_back({"300k", packCloud(depthCameraCloud(640, 480, cam, {table, box}, 0.001), xyzFloat32(), 480)});
  cases.push_back({"2M", packCloud(depthCameraCloud(1920, 1080, cam, {table, box}, 0.001), xyzFloat32(), 1080)});
  cases.push_back({"2M_blob", packCloud(cube)});
  for (const Case& c : cases) {
    const std::size_t total = std::size_t{c.msg.layout.width} * c.msg.layout.height;
    if (c.name != "2M_blob") {
      ObstacleMonitor monitor(robot, ObstacleMapConfig(), obstacle);
      monitor.setJointState(0.0, robot.arm_joints,
                            std::vector<double>(robot.arm_ready.data(), robot.arm_ready.data() + robot.nArm()));
      monitor.setBasePose(0.0, Eigen::Vector3d::Zero());
      int queued = 0;
      ehc_common::benchReport("perception.obstacle_cloud_" + c.name, 20, [&](int) {
        const CloudPoints read = c.msg.extract(static_cast<std::size_t>(obstacle.max_input_points));
        queued = monitor.queueCloud(0.0, transformPoints(read.points, Eigen::Isometry3d::Identity()), cam.translation()).queued;
      }, {{"points", total}, {"read", PointBudget(c.msg.layout.width, c.msg.layout.height, obstacle.max_input_points).selected()}});
      ehc_common::benchPrintValues("perception.obstacle_cloud_" + c.name + ".result", {{"queued", queued}});
    }
    GraspResult last;
    ehc_common::benchReport("perception.grasp_cloud_" + c.name, 5, [&](int) {
      const CloudPoints read = c.msg.extract(static_cast<std::size_t>(targeting.max_input_points));
      last = generateForTarget(gen, transformPoints(read.points, Eigen::Isometry3d::Identity()), cam.translation(),
                               &centre, targeting);
      *sink += static_cast<double>(last.grasps.size());
    }, {{"points", total}, {"read", PointBudget(c.msg.layout.width, c.msg.layout.height, targeting.max_input_points).selected()}});
    ehc_common::benchPrintValues("perception.grasp_cloud_" + c.name + ".result",
                                 {{"grasps", last.grasps.size()}, {"object_points", last.filtered_points},
                                  {"voxel_m", ehc_common::jsonNumber(last.voxel_size)}});
  }
}

}  // namespace

int main(int argc, char** argv) {
  double sink = 0.0;
  if (argc > 1 && std::string(argv[1]) == "grasps") {  // the grasp generator's cases only
    benchGrasps(&sink);
    return sink == 12345.678 ? 1 : 0;
  }
  benchTags();
  benchGrasps(&sink);
  benchObstacles();
  benchCloudPaths(&sink);
  return sink == 12345.678 ? 1 : 0;
}
