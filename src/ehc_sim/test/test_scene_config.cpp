// SceneConfig / SimConfig / FakeRobotConfig: the shipped scenes match the experiments'
// geometry; both simulators' files share one schema for the fake robot; bad files (and the
// kinematic simulator's former keys) fail with a message naming the file and the field; tag
// frame convention.

#include "ehc_control/pinhole_camera.h"
#include "ehc_control/robot_check.h"
#include "ehc_common/config_node.h"
#include "ehc_sim/scene_config.h"
#include "ehc_sim/sim_config.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

using namespace ehc_sim;

namespace {
const std::string kScenes = std::string(EHC_CONFIG_DIR) + "/scenes/";

/// Expects loading `yaml` to throw std::invalid_argument mentioning every string in `parts`.
void expectSceneError(const std::string& yaml, const std::vector<std::string>& parts) {
  try {
    loadSceneConfigString(yaml, "bad_scene.yaml");
    ADD_FAILURE() << "no exception for:\n" << yaml;
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("[SceneConfig]"), std::string::npos) << msg;
    EXPECT_NE(msg.find("bad_scene.yaml"), std::string::npos) << msg;
    for (const auto& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
  }
}

const char* kGoodObject = R"(
scene:
  objects:
    - {name: a, shape: box, size: [0.06, 0.06, 0.12], position: [1.5, 0, 0.06], mass: 0.1,
       tag: {id: 3, size: 0.04, face: "-x"}}
)";
}  // namespace

TEST(SceneConfig, TableThreeObjectsMatchesExperiment2) {
  const SceneConfig s = loadSceneConfig(kScenes + "table_three_objects.yaml");
  ASSERT_EQ(s.tables.size(), 1u);
  const TableConfig& t = s.tables[0];
  EXPECT_NEAR(t.height, 0.75, 1e-12);
  EXPECT_NEAR(t.center.x() - 0.5 * t.size.x(), 1.5, 1e-9) << "near edge 1.5 m in front";
  ASSERT_EQ(s.objects.size(), 3u);
  EXPECT_EQ(s.objects[0].name, "front");
  EXPECT_EQ(s.objects[1].name, "middle");
  EXPECT_EQ(s.objects[2].name, "back");
  const double near = t.center.x() - 0.5 * t.size.x(), far = t.center.x() + 0.5 * t.size.x();
  for (const auto& o : s.objects) {
    // Standing on the top, inside its outline.
    EXPECT_NEAR(o.position.z() - o.halfExtents().z(), t.height, 1e-9) << o.name;
    EXPECT_GT(o.position.x() - o.halfExtents().x(), near) << o.name;
    EXPECT_LT(o.position.x() + o.halfExtents().x(), far) << o.name;
    EXPECT_TRUE(o.tag.enabled) << o.name;
    EXPECT_LE(2 * o.halfExtents().y(), 0.07) << o.name << " must fit the 70 mm gripper";
  }
  EXPECT_LT(s.objects[0].position.x(), s.objects[1].position.x());
  EXPECT_LT(s.objects[1].position.x(), s.objects[2].position.x());
  EXPECT_EQ(s.objects[1].shape, ShapeType::Cylinder);
  // Table = top + 4 legs; the top's upper surface at the table height.
  const auto parts = t.bodies();
  ASSERT_EQ(parts.size(), 5u);
  EXPECT_NEAR(parts[0].position.z() + parts[0].halfExtents().z(), 0.75, 1e-12);
  for (int i = 1; i < 5; ++i) EXPECT_NEAR(parts[i].position.z() - parts[i].halfExtents().z(), 0.0, 1e-12);
}

// `ehc_kinematics --check` asks that the ready pose's camera sees a region ahead
// (ehc_control::RobotCheckParams): by default, every tag of the Exp-2 table seen from the scene's
// start, the four corners of each black square included.
TEST(SceneConfig, TheRobotChecksViewRegionHoldsEveryTagOfTheExp2Table) {
  const SceneConfig s = loadSceneConfig(kScenes + "table_three_objects.yaml");
  const ehc_control::RobotCheckParams p;
  const Eigen::Isometry3d start = Eigen::Translation3d(s.robot_start.x(), s.robot_start.y(), 0.0) *
                                  Eigen::AngleAxisd(s.robot_start.z(), Eigen::Vector3d::UnitZ());
  for (const BodyConfig& o : s.objects) {
    const Eigen::Isometry3d tag = start.inverse() * o.pose() * tagPoseInBody(o);
    for (const double u : {-0.5, 0.5})
      for (const double v : {-0.5, 0.5}) {
        const Eigen::Vector3d c = tag * Eigen::Vector3d(u * o.tag.size, v * o.tag.size, 0.0);
        EXPECT_TRUE((c.array() >= p.view_min.array()).all() && (c.array() <= p.view_max.array()).all())
            << o.name << " tag corner " << c.transpose() << " outside the view region";
      }
  }
}

TEST(SceneConfig, SingleObjectIsOneTaggedObjectAtOnePointFiveMetres) {
  const SceneConfig s = loadSceneConfig(kScenes + "single_object.yaml");
  ASSERT_EQ(s.objects.size(), 1u);
  const BodyConfig& o = s.objects[0];
  EXPECT_TRUE(o.tag.enabled);
  EXPECT_NEAR(o.position.head<2>().norm(), 1.5, 1e-9);
  EXPECT_EQ(s.objectIndex("target"), 0);
  EXPECT_EQ(s.objectIndex("nope"), -1);
  EXPECT_NE(s.summary().find("tag36h11 id 0"), std::string::npos);
}

TEST(SceneConfig, GoodInlineSceneLoads) {
  const SceneConfig s = loadSceneConfigString(kGoodObject, "inline");
  ASSERT_EQ(s.objects.size(), 1u);
  EXPECT_EQ(s.objects[0].tag.id, 3);
  EXPECT_TRUE(s.tables.empty());
}

TEST(SceneConfig, BadFilesNameFileAndField) {
  expectSceneError("scene:\n  objects:\n    - {name: a, size: [0.1, 0.1, 0.1], position: [1, 0, 0.05]}\n",
                   {"objects[0].mass", "missing"});
  expectSceneError("scene:\n  objects:\n    - {name: a, size: [0.1, 0.1], position: [1, 0, 0.05], mass: 1}\n",
                   {"objects[0].size", "3 elements"});
  expectSceneError("scene:\n  objects:\n    - {name: a, shape: cone, size: [0.1, 0.1, 0.1], position: [1, 0, 0.05], mass: 1}\n",
                   {"objects[0].shape", "cone"});
  expectSceneError("scene:\n  objects:\n    - {name: a, size: [0.1, 0.1, 0.1], position: [1, 0, 0.05], mass: -1}\n",
                   {"objects[0].mass"});
  expectSceneError("scene:\n  objects:\n    - {name: a, size: [0.1, 0.1, 0.1], position: [1, 0, 0.05], mass: 1,"
                   " tag: {id: 1, size: 0.09}}\n",
                   {"objects[0].tag.size", "does not fit"});
  expectSceneError("scene:\n  objects:\n    - {name: a, size: [0.1, 0.1, 0.1], position: [1, 0, 0.05], mass: 1,"
                   " tag: {id: 1, size: 0.04, face: top}}\n",
                   {"objects[0].tag.face"});
  expectSceneError("scene:\n  objects:\n    - {name: a, size: [0.1, 0.1, 0.1], position: [1, 0, 0.05], mass: 1,"
                   " tag: {id: 900, size: 0.04}}\n",
                   {"objects[0].tag.id"});
  expectSceneError("scene:\n  tables:\n    - {name: t, size: [0.8, 1.2], center: [2, 0], height: abc}\n",
                   {"tables[0].height", "wrong type"});
  expectSceneError("scene:\n  tables:\n    - {name: t, size: [0.8, 1.2], center: [2, 0], height: 0.7, thickness: 0.9}\n",
                   {"tables[0].thickness"});
  expectSceneError("scene:\n  obstacles:\n    - {name: o, size: [0.1, 0.1, 0.1], position: [1, 0, 0.05], mass: 2}\n",
                   {"obstacles[0].mass", "static"});
  expectSceneError("scene:\n  objects:\n    - {name: a, size: [0.1, 0.1, 0.1], position: [1, 0, 0.05], mass: 1}\n"
                   "  obstacles:\n    - {name: a, size: [0.1, 0.1, 0.1], position: [2, 0, 0.05]}\n",
                   {"'a' is used twice"});
  expectSceneError("scene:\n  objects:\n    - {name: a, size: [0.1, 0.1, 0.1], position: [1, 0, .nan], mass: 1}\n",
                   {"objects[0].position"});
  expectSceneError("scene:\n  objects: {name: a}\n", {"objects", "must be a list"});
  expectSceneError("nothing: 1\n", {"'scene'", "missing"});
  expectSceneError("scene:\n  objects:\n    - {name: a, size: [0.1, 0.1, 0.1], position: [1, 0, 0.01], mass: 1}\n",
                   {"below the floor"});
  // Misspelled keys are errors, never silently ignored (a scene is the experiment's ground truth).
  expectSceneError("scene:\n  objects:\n    - {name: a, size: [0.1, 0.1, 0.1], position: [1, 0, 0.05], mass: 1,"
                   " frction: 0.5}\n",
                   {"unknown field 'scene.objects[0].frction'", "did you mean 'scene.objects[0].friction'"});
  expectSceneError("scene:\n  tabels: []\n", {"unknown field 'scene.tabels'", "did you mean 'scene.tables'"});
}

TEST(SceneConfig, MissingFileIsNamed) {
  try {
    loadSceneConfig("/nonexistent/scene.yaml");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scene.yaml"), std::string::npos);
  }
}

TEST(SceneConfig, TagFrameConvention) {
  BodyConfig b;
  b.size = Eigen::Vector3d(0.06, 0.08, 0.12);
  b.tag.enabled = true;
  b.tag.face = Face::NegX;
  const Eigen::Isometry3d T = tagPoseInBody(b);
  EXPECT_TRUE(T.translation().isApprox(Eigen::Vector3d(-0.03, 0, 0)));
  EXPECT_TRUE(T.linear().col(2).isApprox(-Eigen::Vector3d::UnitX())) << "z out of the face";
  EXPECT_TRUE(T.linear().col(1).isApprox(Eigen::Vector3d::UnitZ())) << "pattern upright";
  EXPECT_TRUE(T.linear().col(0).isApprox(-Eigen::Vector3d::UnitY())) << "x to the viewer's right";
  EXPECT_NEAR(T.linear().determinant(), 1.0, 1e-12);
  for (Face f : {Face::PosX, Face::NegX, Face::PosY, Face::NegY, Face::PosZ, Face::NegZ}) {
    b.tag.face = f;
    const Eigen::Isometry3d Tf = tagPoseInBody(b);
    EXPECT_NEAR(Tf.linear().determinant(), 1.0, 1e-12) << toString(f);
    // The tag centre lies on the face, the tag z axis points out of the body.
    EXPECT_GT((Tf.translation() + 0.01 * Tf.linear().col(2)).cwiseAbs().maxCoeff() -
                  Tf.translation().cwiseAbs().maxCoeff(), 0.0) << toString(f);
  }
}

TEST(SimConfig, ShippedConfigLoadsAndResolvesPaths) {
  const SimConfig c = loadSimConfig(EHC_SIM_CONFIG);
  EXPECT_NEAR(c.fake_robot.dt, 0.01, 1e-15);
  EXPECT_EQ(c.substeps(), 2);
  EXPECT_TRUE(c.fake_robot.noise.enabled);
  EXPECT_NEAR(c.fake_robot.noise.base_translation, 0.05, 1e-15);
  EXPECT_EQ(c.camera.ray_cols, 80);
  EXPECT_EQ(c.camera.ray_rows, 60);
  EXPECT_NO_THROW(loadSceneConfig(c.scene_file));
  EXPECT_TRUE(c.camera_file.empty());  // robot-specific: robot.yaml's robot.camera_info
  const ehc_control::PinholeCamera k =
      ehc_control::loadPinholeCamera(simCameraFile(c, ehc_control::loadRobotConfig(c.fake_robot.robot_file)));
  EXPECT_EQ(k.width, 640);
  EXPECT_NEAR(k.fx, 615.0, 1e-9);
  EXPECT_FALSE(c.summary().empty());
}

TEST(SimConfig, BadValuesNameField) {
  const std::string head = "sim:\n  robot: r.yaml\n  camera_info: c.yaml\n";
  auto expectError = [&](const std::string& body, const std::string& field) {
    try {
      loadSimConfigString(head + body, "bad_sim.yaml");
      ADD_FAILURE() << body;
    } catch (const std::invalid_argument& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("bad_sim.yaml"), std::string::npos) << msg;
      EXPECT_NE(msg.find(field), std::string::npos) << msg;
    }
  };
  expectError("  dt: 0\n", "sim.dt");
  expectError("  dt: fast\n", "sim.dt");
  expectError("  noise: {arm: -1}\n", "sim.noise.arm");
  expectError("  gripper: {speed: 0}\n", "sim.gripper.speed");
  expectError("  camera: {ray_grid: [80]}\n", "sim.camera.ray_grid");
  expectError("  camera: {min_range: 7, max_range: 6}\n", "sim.camera.min_range");
  expectError("  camera: {depth_noise: {base: 1}}\n", "sim.camera.depth_noise.base");
  expectError("  collision: {ignore_pairs: [[a, b]]}\n", "sim.collision.ignore_pairs");  // robot.yaml's now
  expectError("  collision: {floor_links: [base_link]}\n", "sim.collision.floor_links");
  expectError("  collision: {self_collision_samples: 0}\n", "samples");
  expectError("  seed: -4\n", "sim.seed");
  expectError("  camera: {ray_gird: [80, 60]}\n", "unknown field 'sim.camera.ray_gird'");
  try {
    loadSimConfigString("sim:\n  camera_info: c.yaml\n", "bad_sim.yaml");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sim.robot"), std::string::npos) << e.what();
  }
}

TEST(FakeRobotConfig, BothSimulatorsReadTheSameSchema) {
  const SimConfig bullet = loadSimConfig(EHC_SIM_CONFIG);
  const FakeRobotConfig kin = loadFakeRobotConfigFile(std::string(EHC_CONFIG_DIR) + "/sim/kinematic_sim.yaml");
  EXPECT_EQ(kin.robot_file, bullet.fake_robot.robot_file);  // same folder, same relative path
  EXPECT_EQ(kin.dt, bullet.fake_robot.dt);
  EXPECT_EQ(kin.dtNs(), 10'000'000);
  EXPECT_FALSE(kin.free_run);
  EXPECT_EQ(kin.state_republish_period, bullet.fake_robot.state_republish_period);
  EXPECT_EQ(kin.command_timeout, bullet.fake_robot.command_timeout);
  EXPECT_FALSE(kin.noise.enabled) << "controller tests run without noise";
  EXPECT_EQ(kin.noise.base_translation, bullet.fake_robot.noise.base_translation);
  EXPECT_EQ(kin.noise.arm, bullet.fake_robot.noise.arm);
  EXPECT_TRUE(kin.robot_start.isZero());
  EXPECT_NO_THROW(ehc_control::loadRobotConfig(kin.robot_file));
  EXPECT_FALSE(kin.summary().empty());

  const FakeRobotConfig moved = loadFakeRobotConfig(
      ehc_common::ConfigNode::loadString("sim:\n  robot: r.yaml\n  robot_start: {x: 1.5, yaw: 0.3}\n",
                                          "k.yaml", "FakeRobotConfig").child("sim"));
  EXPECT_EQ(moved.robot_start, Eigen::Vector3d(1.5, 0.0, 0.3));
}

TEST(FakeRobotConfig, FormerKinematicKeysAreErrorsNamingFileAndField) {
  auto expectError = [](const std::string& body, const std::string& field, const std::string& hint) {
    try {
      loadFakeRobotConfig(ehc_common::ConfigNode::loadString("sim:\n  robot: r.yaml\n" + body, "old_kin.yaml",
                                                              "FakeRobotConfig").child("sim"));
      ADD_FAILURE() << body;
    } catch (const std::invalid_argument& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("old_kin.yaml"), std::string::npos) << msg;
      EXPECT_NE(msg.find(field), std::string::npos) << msg;
      EXPECT_NE(msg.find(hint), std::string::npos) << msg;
    }
  };
  expectError("  lockstep: true\n", "sim.lockstep", "sim.free_run");
  expectError("  lockstep_timeout_wall: 1.0\n", "sim.lockstep_timeout_wall", "state_republish_period");
  expectError("  noise: false\n", "sim.noise", "enabled: false");
  expectError("  noise_base_translation: 0.05\n", "sim.noise_base_translation", "sim.noise.base_translation");
  expectError("  noise_base_rotation: 0.05\n", "sim.noise_base_rotation", "sim.noise.base_rotation");
  expectError("  noise_arm: 0.002\n", "sim.noise_arm", "sim.noise.arm");
  expectError("  initial_base: [0, 0, 0]\n", "sim.initial_base", "sim.robot_start");
  expectError("  dt: 0.0100000001\n", "sim.dt", "nanoseconds");

  // The robot file moved under sim; unknown top-level keys are errors too.
  const std::string path = testing::TempDir() + "/old_kinematic_sim.yaml";
  std::ofstream(path) << "sim:\n  robot: r.yaml\n  camera_info: c.yaml\n";
  try {
    loadFakeRobotConfigFile(path);
    ADD_FAILURE() << "a Bullet key in the kinematic file";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("field 'sim.camera_info'"), std::string::npos) << e.what();
  }
  for (const std::string& top : {std::string("robot: r.yaml\n"), std::string("simulation: {}\n")}) {
    std::ofstream(path) << top << "sim:\n  robot: r.yaml\n";
    try {
      loadFakeRobotConfigFile(path);
      ADD_FAILURE() << top;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("field '" + top.substr(0, top.find(':')) + "'"), std::string::npos)
          << e.what();
    }
  }
}

TEST(SimConfig, RobotStartComesFromTheScene) {
  try {
    loadSimConfigString("sim:\n  robot: r.yaml\n  camera_info: c.yaml\n  robot_start: {x: 1}\n", "bad_sim.yaml");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sim.robot_start"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("scene"), std::string::npos) << e.what();
  }
}

TEST(SceneConfig, TargetsSelectObjectsWithoutTagsAndBadOnesNameFileAndField) {
  const std::string objects = R"(
scene:
  objects:
    - {name: a, shape: box, size: [0.06, 0.06, 0.12], position: [1.5, 0, 0.06], mass: 0.1,
       tag: {id: 3, size: 0.04, face: "-x"}}
    - {name: b, shape: box, size: [0.06, 0.06, 0.12], position: [1.5, 0.2, 0.06], mass: 0.1}
)";
  const SceneConfig s = loadSceneConfigString(objects + R"(  targets:
    - {select: kth_from_left, k: 2}
    - {select: nearest, point: [1.5, 0.2, 0.06]}
    - {select: tag, tag_id: 3}
)", "good_scene.yaml");
  ASSERT_EQ(s.targets.size(), 3u);
  EXPECT_EQ(s.targets[0].kind, ehc_control::TargetSelectorKind::KthFromLeft);
  EXPECT_EQ(s.targets[1].kind, ehc_control::TargetSelectorKind::Nearest);
  EXPECT_EQ(s.targets[2].tag_id, 3);
  EXPECT_TRUE(loadSceneConfigString(kGoodObject, "no_targets.yaml").targets.empty());  // tags, as before
  expectSceneError(objects + "  targets:\n    - {select: largest}\n", {"scene.targets[0].select", "largest"});
  expectSceneError(objects + "  targets:\n    - {select: kth_from_front, k: 3}\n",
                   {"scene.targets[0].k", "out of range", "2 object(s)"});
  expectSceneError(objects + "  targets:\n    - {select: kth_from_front, k: 1}\n    - {select: kth_from_left, k: 0}\n",
                   {"scene.targets[1].k"});
  expectSceneError(objects + "  targets:\n    - {select: tag, tag_id: 4}\n", {"scene.targets[0].tag_id", "none of"});
}
