// Mesh objects in the simulator: OBJ, STL and PLY files read back as written; a missing, empty,
// degenerate or huge mesh is a start-up error naming the file; the object library's manifest is
// what its generator gives (sizes, masses, both splits of every kind) and its mesh files load;
// library objects dropped on a table come to rest on it, the depth camera measures their
// triangles exactly and the grey image draws them.

#include "ehc_sim/object_library.h"
#include "ehc_sim/scene_config.h"
#include "ehc_sim/sim_world.h"
#include "ehc_sim/simulated_camera.h"
#include "ehc_sim/triangle_mesh.h"

#include <gtest/gtest.h>

#include "ehc_control/pose_math.h"
#include "ehc_test/errors.h"

#include <cstdio>
#include <fstream>
#include <set>
#include <unistd.h>

using namespace ehc_sim;

namespace {
const std::string kConfig = std::string(EHC_CONFIG_DIR);

std::string tempPath(const std::string& name) {
  return "/tmp/ehc_sim_test_mesh_" + std::to_string(getpid()) + "_" + name;
}

/// Distance from p to the triangle (a, b, c) (closest point by region, Ericson's method).
double pointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return (p - a).norm();
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return (p - b).norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return (p - c).norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
  const double denom = 1.0 / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

double meshDistance(const TriangleMesh& m, const Eigen::Vector3d& p) {
  double best = 1e9;
  for (const auto& t : m.triangles)
    best = std::min(best, pointTriangleDistance(p, m.vertices[static_cast<std::size_t>(t[0])],
                                                m.vertices[static_cast<std::size_t>(t[1])], m.vertices[static_cast<std::size_t>(t[2])]));
  return best;
}

void writeText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }
}  // namespace

TEST(MeshFiles, ObjStlAndPlyReadBackAsWritten) {
  const std::map<std::string, double> params = drawObjectParams("mug", 7);
  const TriangleMesh mug = generateObjectMesh("mug", params, 7);
  for (const std::string ext : {"obj", "stl", "ply"}) {
    const std::string path = tempPath("mug." + ext);
    writeMeshFile(mug, path);
    const TriangleMesh back = loadObjectMesh(path, 1.0);
    std::remove(path.c_str());
    SCOPED_TRACE(ext);
    EXPECT_EQ(back.triangles.size(), mug.triangles.size());
    const Eigen::Vector3d extent = mug.boundsMax() - mug.boundsMin();
    EXPECT_LT(((back.boundsMax() - back.boundsMin()) - extent).norm(), 1e-6);
    EXPECT_LT((back.boundsMax() + back.boundsMin()).norm(), 1e-6) << "centred on its bounding box";
    EXPECT_NEAR(back.solidVolume(), mug.solidVolume(), 1e-3 * mug.solidVolume());
    EXPECT_EQ(back.components().size(), mug.components().size());
  }
  // scale: file units to metres
  const std::string mm = tempPath("mug_mm.obj");
  TriangleMesh big = mug;
  for (auto& v : big.vertices) v *= 1000.0;
  writeMeshFile(big, mm);
  const TriangleMesh scaled = loadObjectMesh(mm, 0.001);
  std::remove(mm.c_str());
  EXPECT_LT(((scaled.boundsMax() - scaled.boundsMin()) - (mug.boundsMax() - mug.boundsMin())).norm(), 1e-6);
}

TEST(MeshFiles, MissingEmptyDegenerateOrHugeMeshesAreErrorsNamingTheFile) {
  using ehc_test::errorOf;
  const std::string missing = tempPath("missing.obj");
  EXPECT_NE(errorOf([&] { loadObjectMesh(missing, 1.0); }).find(missing + ": mesh file not found"), std::string::npos);
  const std::string empty = tempPath("empty.obj");
  writeText(empty, "# no faces\nv 0 0 0\nv 1 0 0\n");
  EXPECT_NE(errorOf([&] { loadObjectMesh(empty, 1.0); }).find(empty), std::string::npos);
  const std::string flat = tempPath("flat.obj");
  writeText(flat, "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0.1 0.1 0\nf 1 2 3\nf 2 4 3\n");
  EXPECT_NE(errorOf([&] { loadObjectMesh(flat, 1.0); }).find(flat + ": is degenerate"), std::string::npos);
  const std::string line = tempPath("line.obj");
  writeText(line, "v 0 0 0\nv 0.1 0 0\nv 0.2 0 0\nf 1 2 3\n");
  EXPECT_NE(errorOf([&] { loadObjectMesh(line, 1.0); }).find(line + ": is degenerate"), std::string::npos);
  const std::string cube = tempPath("cube.stl");
  writeMeshFile(boxSurface(Eigen::Vector3d(0.05, 0.05, 0.05)), cube);
  EXPECT_NE(errorOf([&] { loadObjectMesh(cube, 1000.0); }).find(cube + ": is huge"), std::string::npos) << "mm read as m";
  EXPECT_NO_THROW(loadObjectMesh(cube, 1.0));
  EXPECT_NE(errorOf([&] { loadObjectMesh(tempPath("x.dae"), 1.0); }).find("not an OBJ, STL or PLY"), std::string::npos);
  // In a scene: the scene file, the field and the mesh file are named.
  const std::string scene = tempPath("scene.yaml");
  writeText(scene, "scene:\n  objects:\n    - {name: thing, shape: mesh, mesh: " + missing + ", position: [1, 0, 0.1], mass: 0.1}\n");
  const std::string e = errorOf([&] { loadSceneConfig(scene); });
  EXPECT_NE(e.find(scene), std::string::npos) << e;
  EXPECT_NE(e.find("objects[0].mesh"), std::string::npos) << e;
  EXPECT_NE(e.find(missing), std::string::npos) << e;
  writeText(scene, "scene:\n  objects:\n    - {name: thing, shape: mesh, mesh: " + cube + ", size: [1, 1, 1], position: [1, 0, 0.1], mass: 0.1}\n");
  EXPECT_NE(errorOf([&] { loadSceneConfig(scene); }).find("objects[0].size"), std::string::npos);
  // A relative mesh path is read against the scene's folder; a tag sits on the mesh's surface.
  writeText(scene, "scene:\n  objects:\n    - {name: thing, shape: mesh, mesh: " + cube.substr(cube.rfind('/') + 1) +
                       ", position: [1, 0, 0.1], mass: 0.1, tag: {id: 3, size: 0.03, face: -x}}\n");
  const SceneConfig s = loadSceneConfig(scene);
  ASSERT_EQ(s.objects.size(), 1u);
  EXPECT_EQ(s.objects[0].shape, ShapeType::Mesh);
  EXPECT_NEAR(s.objects[0].size.x(), 0.05, 1e-6);
  EXPECT_NEAR(tagPoseInBody(s.objects[0]).translation().x(), -0.025, 1e-6);
  for (const auto& f : {empty, flat, line, cube, scene}) std::remove(f.c_str());
}

TEST(ObjectLibrary, TheManifestIsWhatItsGeneratorGivesWithBothSplitsOfEveryKind) {
  const ObjectLibrary lib = loadObjectLibrary(kConfig + "/objects/library.yaml");
  ASSERT_GE(lib.objects.size(), 30u);
  std::set<std::string> tuning, validation;
  int per_kind = 0;
  for (const LibraryObject& o : lib.objects) {
    SCOPED_TRACE(o.name);
    (o.split == "tuning" ? tuning : validation).insert(o.kind);
    per_kind += o.kind == lib.objects.front().kind;
    const TriangleMesh m = generateObjectMesh(o.kind, o.params, o.seed);
    const Eigen::Vector3d size = m.boundsMax() - m.boundsMin();
    EXPECT_LT((size - o.size).cwiseAbs().maxCoeff(), 1e-4);
    const double density = o.params.at("density");
    EXPECT_NEAR(o.mass, density * m.solidVolume(), 1e-4 + 1e-3 * o.mass);
    // Plausible everyday objects: 2 cm .. 30 cm, 20 g .. 1.5 kg, the density of a real material.
    EXPECT_GE(size.minCoeff(), 0.003);
    EXPECT_LE(size.maxCoeff(), 0.30);
    EXPECT_GE(o.mass, 0.02);
    EXPECT_LE(o.mass, 1.5);
    EXPECT_GE(density, 100.0);
    EXPECT_LE(density, 8000.0);
    // The mesh file the build wrote is the generator's.
    const TriangleMesh file = loadObjectMesh(lib.meshPath(o), 1.0);
    EXPECT_EQ(file.triangles.size(), m.triangles.size());
    EXPECT_LT(((file.boundsMax() - file.boundsMin()) - size).norm(), 1e-5);
  }
  EXPECT_EQ(tuning, std::set<std::string>(objectKinds().begin(), objectKinds().end()));
  EXPECT_EQ(validation, tuning);
  // Reproducible: the manifest's seed draws the same objects again.
  const ObjectLibrary again = drawObjectLibrary(lib.seed, per_kind);
  ASSERT_EQ(again.objects.size(), lib.objects.size());
  for (std::size_t i = 0; i < again.objects.size(); ++i) {
    EXPECT_EQ(again.objects[i].name, lib.objects[i].name);
    EXPECT_EQ(again.objects[i].params, lib.objects[i].params) << lib.objects[i].name;
    EXPECT_NEAR(again.objects[i].mass, lib.objects[i].mass, 1e-4);
  }
}

namespace {
struct TableRig {
  SimConfig cfg;
  std::unique_ptr<SimWorld> world;
  std::unique_ptr<SimulatedCamera> camera;
  /// The library objects `names` in a row across the table, dropped from 5 mm above it.
  TableRig(const std::vector<std::string>& names, bool noise) : TableRig(inARow(names), noise) {}
  static std::vector<BodyConfig> inARow(const std::vector<std::string>& names) {
    const ObjectLibrary lib = loadObjectLibrary(kConfig + "/objects/library.yaml");
    std::vector<BodyConfig> objects;
    double y = -0.4;
    for (const auto& n : names) {
      BodyConfig b = libraryBody(lib, n);
      b.shade = 40;  // darker than the table and the floor: the image test counts its pixels
      b.position = Eigen::Vector3d(1.9, y, 0.75 + b.halfExtents().z() + 0.005);
      y += 0.8 / static_cast<double>(names.size() - 1);
      objects.push_back(b);
    }
    return objects;
  }
  TableRig(const std::vector<BodyConfig>& objects, bool noise) {
    cfg = loadSimConfig(EHC_SIM_CONFIG);
    if (!noise) {
      cfg.camera.image_noise = 0.0;
      cfg.camera.depth_noise.model = DepthNoiseModel::Gaussian;
      cfg.camera.depth_noise.base = cfg.camera.depth_noise.quadratic = 0.0;
    }
    SceneConfig scene;
    scene.tables.push_back(TableConfig());
    scene.tables[0].name = "table";
    scene.objects = objects;
    const ehc_control::RobotConfig robot = ehc_control::loadRobotConfig(cfg.fake_robot.robot_file);
    world = std::make_unique<SimWorld>(cfg, robot, scene);
    camera = std::make_unique<SimulatedCamera>(ehc_control::loadPinholeCamera(simCameraFile(cfg, robot)), cfg.camera, 3);
    camera->setScene(world->bodies(), scene.floor_shade);
  }
  void settle(double seconds) {
    const Eigen::VectorXd still = Eigen::VectorXd::Zero(world->robot().nDof());
    const double t_end = world->time() + seconds;
    while (world->time() < t_end) world->step(still);
  }
};
const std::vector<std::string> kOnTable = {"mug_01", "banana_02", "bars_01", "bottle_02", "tool_01"};
}  // namespace

TEST(MeshObjects, LibraryObjectsComeToRestOnTheTable) {
  TableRig rig(kOnTable, false);
  rig.settle(1.5);
  std::vector<Eigen::Isometry3d> before;
  for (std::size_t i = 0; i < kOnTable.size(); ++i) before.push_back(rig.world->objectPose(static_cast<int>(i)));
  rig.settle(0.3);
  for (std::size_t i = 0; i < kOnTable.size(); ++i) {
    SCOPED_TRACE(kOnTable[i]);
    const Eigen::Isometry3d T = rig.world->objectPose(static_cast<int>(i));
    EXPECT_LT((T.translation() - before[i].translation()).norm(), 0.002) << "at rest";
    // Its lowest vertex is on the table top (within the hull's 1 mm margin and a little sinking).
    double lowest = 1e9;
    for (const auto& v : rig.world->bodySurface(rig.world->objectBodyIndex(static_cast<int>(i))).vertices)
      lowest = std::min(lowest, (T * v).z());
    EXPECT_NEAR(lowest, 0.75, 0.003);
    EXPECT_LT((T.translation().head<2>() - rig.world->scene().objects[i].position.head<2>()).norm(), 0.05);
  }
}

// The simulator collides a mesh as the convex hulls of its connected parts: a cup or a bowl of
// one part would be a solid that no finger enters (a wall grasp's inner finger flung the bowl
// away; a cube put inside was thrown out). Every library cup and bowl is open: a 15 mm cube put
// inside on its axis comes to rest on its floor, and the cup stays upright.
TEST(MeshObjects, ACubePutIntoEveryCupAndBowlRestsOnItsFloor) {
  const ObjectLibrary lib = loadObjectLibrary(kConfig + "/objects/library.yaml");
  std::vector<BodyConfig> bodies;
  std::vector<const LibraryObject*> containers;
  for (const LibraryObject& o : lib.objects)
    if (o.kind == "mug" || o.kind == "bowl") containers.push_back(&o);
  ASSERT_EQ(containers.size(), 8u);
  for (std::size_t i = 0; i < containers.size(); ++i) {
    BodyConfig b = libraryBody(lib, containers[i]->name);
    b.position = Eigen::Vector3d(i % 2 ? 2.05 : 1.75, -0.45 + 0.3 * static_cast<double>(i / 2), 0.75 + b.halfExtents().z() + 0.002);
    bodies.push_back(b);
  }
  for (std::size_t i = 0; i < containers.size(); ++i) {
    const BodyConfig& c = bodies[i];
    // The axis: the mesh is centred on its bounding box, the handle (a mug's) on its +y side.
    const double axis_y = containers[i]->params.at("radius") - c.halfExtents().y();
    BodyConfig cube;
    cube.name = "cube_" + std::to_string(i);
    cube.shape = ShapeType::Box;
    cube.size = Eigen::Vector3d::Constant(0.015);
    cube.mass = 0.01;
    // 3 mm above the inside's floor (a mug's base is 8 mm thick, a bowl's its wall): a drop from
    // above the rim would pass the thin base in one physics step.
    const double floor = containers[i]->kind == "mug" ? 0.008 : containers[i]->params.at("wall");
    cube.position = c.position + Eigen::Vector3d(0.0, axis_y, -c.halfExtents().z() + floor + 0.0075 + 0.003);
    bodies.push_back(cube);
  }
  TableRig rig(bodies, false);
  rig.settle(1.5);
  for (std::size_t i = 0; i < containers.size(); ++i) {
    SCOPED_TRACE(containers[i]->name);
    const Eigen::Isometry3d cup = rig.world->objectPose(static_cast<int>(i));
    const Eigen::Isometry3d cube = rig.world->objectPose(static_cast<int>(containers.size() + i));
    const double height = 2.0 * bodies[i].halfExtents().z();
    std::printf("%s: upright cos %.4f, cup bottom %.4f, cube at %.4f above the table (cup height %.4f), %.4f from the cup's centre\n",
                containers[i]->name.c_str(), cup.linear().col(2).z(), cup.translation().z() - 0.5 * height - 0.75, cube.translation().z() - 0.75, height,
                (cube.translation() - cup.translation()).head<2>().norm());
    EXPECT_GT(cup.linear().col(2).z(), std::cos(5.0 * M_PI / 180.0)) << "upright";
    const double floor = containers[i]->kind == "mug" ? 0.008 : containers[i]->params.at("wall");
    EXPECT_NEAR(cube.translation().z(), 0.75 + floor + 0.0075, 0.003) << "on the floor inside (cup height " << height << " m)";
    EXPECT_LT((cube.translation() - cup.translation()).head<2>().norm(), containers[i]->params.at("radius")) << "inside the rim";
  }
}

TEST(MeshObjects, TheDepthCameraMeasuresTheTrianglesAndTheImageDrawsThem) {
  TableRig rig(kOnTable, false);
  rig.settle(1.0);
  for (std::size_t i = 0; i < kOnTable.size(); ++i) {
    SCOPED_TRACE(kOnTable[i]);
    const int body = rig.world->objectBodyIndex(static_cast<int>(i));
    const Eigen::Isometry3d T = rig.world->objectPose(static_cast<int>(i));
    const TriangleMesh& mesh = rig.world->bodySurface(body);
    const Eigen::Isometry3d T_cam = ehc_control::lookAt(T.translation() + Eigen::Vector3d(-0.35, 0.05, 0.3), T.translation());
    std::vector<Eigen::Vector3f> pts;
    rig.camera->cloud(*rig.world, T_cam, &pts);
    int on_object = 0;
    double worst = 0.0;
    for (const auto& pc : pts) {
      const Eigen::Vector3d p = T.inverse() * (T_cam * pc.cast<double>());
      if (((p.cwiseAbs() - rig.world->bodies()[static_cast<std::size_t>(body)].halfExtents()).array() > 0.002).any()) continue;
      if ((T * p).z() < 0.752) continue;  // the table top
      worst = std::max(worst, meshDistance(mesh, p));
      ++on_object;
    }
    EXPECT_GT(on_object, 20);
    EXPECT_LT(worst, 1e-5) << "every point on the object lies on its triangles";
    // The image: the object's centre pixel has the object's shade (not the table's or the floor's).
    vpImage<unsigned char> I;
    std::vector<Eigen::Isometry3d> poses;
    for (std::size_t b = 0; b < rig.world->bodies().size(); ++b) poses.push_back(rig.world->bodyPose(static_cast<int>(b)));
    rig.camera->render(T_cam, poses, &I);
    int object_pixels = 0;
    for (unsigned k = 0; k < I.getSize(); ++k) object_pixels += I.bitmap[k] <= 40;
    EXPECT_GT(object_pixels, 1000) << "drawn (shade 40; the table and the floor are brighter)";
  }
}

// The shipped scene with library meshes beside the demo's tagged objects: it loads (relative
// mesh paths), its mesh objects settle where they were put, and the tagged can's tag is in view
// from in front of the table.
TEST(MeshObjects, TheMeshSceneLoadsAndSettles) {
  const SceneConfig scene = loadSceneConfig(kConfig + "/scenes/table_mesh_objects.yaml");
  SimConfig cfg = loadSimConfig(EHC_SIM_CONFIG);
  const ehc_control::RobotConfig robot = ehc_control::loadRobotConfig(cfg.fake_robot.robot_file);
  SimWorld world(cfg, robot, scene);
  const Eigen::VectorXd still = Eigen::VectorXd::Zero(world.robot().nDof());
  while (world.time() < 1.5) world.step(still);
  int meshes = 0;
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    const Eigen::Vector3d p = world.objectPose(static_cast<int>(i)).translation();
    EXPECT_LT((p - scene.objects[i].position).norm(), 0.01) << scene.objects[i].name;
    meshes += scene.objects[i].shape == ShapeType::Mesh;
  }
  EXPECT_EQ(meshes, 3);
  EXPECT_FALSE(world.lastStep().robot_world_collision);
  SimulatedCamera camera(ehc_control::loadPinholeCamera(simCameraFile(cfg, robot)), cfg.camera, 1);
  SceneConfig can_only = scene;
  for (auto& o : can_only.objects) o.tag.enabled = o.name == "can";
  camera.setScene(SimWorld(cfg, robot, can_only).bodies(), scene.floor_shade);
  const Eigen::Vector3d can = world.objectPose(scene.objectIndex("can")).translation();
  std::vector<Eigen::Isometry3d> poses;
  for (std::size_t b = 0; b < world.bodies().size(); ++b) poses.push_back(world.bodyPose(static_cast<int>(b)));
  EXPECT_TRUE(camera.tagInView(ehc_control::lookAt(can + Eigen::Vector3d(-0.5, 0.0, 0.25), can), poses));
}
