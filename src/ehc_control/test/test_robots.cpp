// Any mobile manipulator from a URDF + robot.yaml. Over every shipped robot (every folder under
// config/robots: the RealMan RM65 and the Kinova Gen3 on differential bases, the KUKA iiwa 14 and
// the UR5e on holonomic bases): the robot switch
// resolves the name, the description loads, its map fits and matches, the self-collision pairs
// are computed; a minimal robot.yaml is enough; a link robot.yaml names that the URDF lacks, an
// unknown robot and an arm of other than 6 or 7 joints are start-up errors naming the field.

#include "ehc_common/config_node.h"
#include "ehc_control/control_cycle.h"
#include "ehc_control/reachability_map.h"
#include "ehc_control/robot_collision_model.h"
#include "ehc_control/robot_config.h"
#include "ehc_control/self_collision.h"
#include "ehc_control/whole_body_model.h"
#include "ehc_test/control_fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

using namespace ehc_control;
using ehc_control::test::errorOf;

namespace {

const std::string kConfigDir = EHC_CONFIG_DIR;
const std::string kKukaUrdf = kConfigDir + "/robots/kuka_iiwa14_kmr/robot.urdf";

/// The minimal robot.yaml of the README's "Bring your own robot", for the KUKA's URDF.
std::string minimalYaml(const std::string& arm_joints, const std::string& extra = "") {
  return "robot:\n  urdf: " + kKukaUrdf +
         "\n  frames: {base: base_link, arm_base: iiwa_link_0, tcp: ee_link, camera_optical: camera_color_optical_frame}\n"
         "  base: {type: holonomic, max_linear_velocity: 0.5, max_angular_velocity: 0.7}\n"
         "  arm:\n    joints: [" + arm_joints + "]\n"
         "    lower: [-2.9, -2.0, -2.9, -2.0, -2.9, -2.0, -3.0]\n"
         "    upper: [2.9, 2.0, 2.9, 2.0, 2.9, 2.0, 3.0]\n"
         "    velocity: [1.4, 1.4, 1.7, 1.3, 2.2, 2.3, 2.3]\n"
         "    ready: [0.0, 0.562, 0.0, -1.548, 0.0, -0.209, 0.0]\n" + extra;
}
const std::string kIiwaJoints =
    "iiwa_joint_1, iiwa_joint_2, iiwa_joint_3, iiwa_joint_4, iiwa_joint_5, iiwa_joint_6, iiwa_joint_7";

std::string writeTemp(const std::string& text) {
  const std::string path = ::testing::TempDir() + "/ehc_robot_" + std::to_string(std::hash<std::string>{}(text)) + ".yaml";
  std::ofstream(path) << text;
  return path;
}

class ShippedRobot : public ::testing::TestWithParam<std::string> {};

}  // namespace

TEST_P(ShippedRobot, LoadsByNameWithItsMapAndSelfCollisionPairs) {
  const std::string file = resolveRobotFile(GetParam());
  EXPECT_TRUE(std::filesystem::equivalent(file, kConfigDir + "/robots/" + GetParam() + "/robot.yaml")) << file;
  const RobotConfig rc = loadRobotConfig(file);
  EXPECT_TRUE(rc.nArm() == 6 || rc.nArm() == 7);
  const WholeBodyModel model(rc);
  // The map (<= 5 MB) belongs to this arm, TCP and limits.
  ASSERT_FALSE(rc.reachability_map_path.empty());
  EXPECT_LE(std::filesystem::file_size(rc.reachability_map_path), 5u * 1024u * 1024u);
  EXPECT_NO_THROW(ReachabilityMap::load(rc.reachability_map_path).checkCompatible(model));
  EXPECT_FALSE(rc.camera_info_path.empty());
  // Checked links: robot.yaml's, or every link with collision geometry.
  const RobotCollisionModel collision(model.urdfXml(), rc.arm_joints, rc.checked_links);
  EXPECT_GE(collision.links().size(), 10u);
  EXPECT_EQ(collision.fingers().size(), 2u);  // the grasp pipeline's parallel gripper
  // Self-collision pairs: every adjacent pair, robot.yaml's extra pairs, and nothing that is
  // apart in the ready pose (an always-colliding pair is in contact in every sample).
  const auto pairs = selfCollisionIgnorePairs(model, collision);
  for (const auto& l : collision.links())
    for (const auto& m : collision.links())
      if (l.name < m.name && collision.adjacent(l.name, m.name)) {
        EXPECT_TRUE(std::count(pairs.begin(), pairs.end(), LinkPair{l.name, m.name})) << l.name << " " << m.name;
      }
  for (const auto& [a, b] : rc.ignore_pairs)
    EXPECT_TRUE(std::count(pairs.begin(), pairs.end(), a < b ? LinkPair{a, b} : LinkPair{b, a}));
  const auto always = alwaysCollidingPairs(model, collision, {200, 3});
  for (const LinkPair& p : always) EXPECT_TRUE(std::count(pairs.begin(), pairs.end(), p));
  // The shipped controller.yaml runs this robot (the one switch: robot_file).
  ControlCycleParams params = loadControlCycleParams(ehc_common::ConfigNode::loadFile(kConfigDir + "/control/controller.yaml", "test"));
  params.robot_file = file;
  const ControlCycle cycle(params);
  EXPECT_EQ(cycle.model().config().name, GetParam());
  for (const auto& [link, d] : rc.obstacle_stop_distances) EXPECT_EQ(cycle.controller().params().obstacleStop(link), d);
}

INSTANTIATE_TEST_SUITE_P(Robots, ShippedRobot, ::testing::ValuesIn(robotNames()), [](const auto& info) { return info.param; });

TEST(RobotSwitch, ResolvesNamesAndPathsAndNamesTheKnownRobots) {
  EXPECT_EQ(resolveRobotFile("some/dir/robot.yaml"), "some/dir/robot.yaml");
  EXPECT_EQ(resolveRobotFile("robot.yaml"), "robot.yaml");
  const std::string e = errorOf([] { resolveRobotFile("no_such_robot"); });
  EXPECT_NE(e.find("unknown robot 'no_such_robot'"), std::string::npos) << e;
  for (const std::string& robot : robotNames()) EXPECT_NE(e.find(robot), std::string::npos) << e;
  const std::vector<std::string> names = robotNames();  // sorted
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
  for (const char* shipped : {"kinova_gen3_husky", "kuka_iiwa14_kmr", "realman_rm65_water2", "ur5e_ridgeback"})
    EXPECT_TRUE(std::count(names.begin(), names.end(), shipped)) << shipped;
}

TEST(RobotSwitch, AUsersRobotsFolderStillFindsTheShippedRobots) {
  // EHC_ROBOTS_DIR with only the user's robot: its robot by name, and the shipped robot the
  // generic configs name (before: looked up in the user's folder only, so every tool that
  // loads config/control/controller.yaml failed, even with --robot <the user's robot>).
  namespace fs = std::filesystem;
  const std::string dir = ::testing::TempDir() + "/ehc_user_robots";
  fs::remove_all(dir);
  fs::create_directories(dir + "/my_robot");
  for (const char* f : {"robot.yaml", "robot.urdf", "camera.yaml", "reachability_map.bin"})
    fs::copy_file(kConfigDir + "/robots/kuka_iiwa14_kmr/" + f, dir + "/my_robot/" + f);
  ::setenv("EHC_ROBOTS_DIR", dir.c_str(), 1);
  EXPECT_EQ(resolveRobotFile("my_robot"), dir + "/my_robot/robot.yaml");
  const std::string shipped = configDirectory() + "/robots";
  EXPECT_EQ(resolveRobotFile("realman_rm65_water2"), shipped + "/realman_rm65_water2/robot.yaml");
  ControlCycleParams p = loadControlCycleParams(ehc_common::ConfigNode::loadFile(kConfigDir + "/control/controller.yaml", "test"));
  EXPECT_EQ(p.robot_file, shipped + "/realman_rm65_water2/robot.yaml");
  p.robot_file = resolveRobotFile("my_robot");
  EXPECT_EQ(ControlCycle(p).model().nBase(), 3);
  const std::string e = errorOf([] { resolveRobotFile("nobody"); });
  EXPECT_NE(e.find("robots in " + dir + ": my_robot"), std::string::npos) << e;
  EXPECT_NE(e.find("robots in " + shipped + ": "), std::string::npos) << e;
  ::unsetenv("EHC_ROBOTS_DIR");
  fs::remove_all(dir);
}

TEST(MinimalRobotYaml, IsEnoughAndDefaultsTheLinkLists) {
  const RobotConfig rc = loadRobotConfig(writeTemp(minimalYaml(kIiwaJoints)));
  EXPECT_TRUE(rc.checked_links.empty());
  EXPECT_TRUE(rc.floor_links.empty());
  EXPECT_TRUE(rc.obstacle_stop_distances.empty());
  const WholeBodyModel model(rc);
  EXPECT_EQ(model.nBase(), 3);
  const RobotCollisionModel collision(model.urdfXml(), rc.arm_joints, rc.checked_links);
  // Every link with collision geometry: platform, arm base, 7 links, gripper, 2 fingers, camera.
  EXPECT_EQ(collision.links().size(), 13u);
  EXPECT_FALSE(selfCollisionIgnorePairs(model, collision, {100, 1}).empty());
}

TEST(MinimalRobotYaml, NamesTheRobotDoesNotHaveAreStartUpErrors) {
  for (const std::string& extra :
       {std::string("  collision: {checked_links: [base_link, link3]}\n"),
        std::string("  collision: {floor_links: [wheel_link]}\n"),
        std::string("  collision: {ignore_pairs: [[iiwa_link_3, link5]]}\n"),
        std::string("  obstacle_stop_distances: {link6: 0.02}\n")}) {
    const std::string file = writeTemp(minimalYaml(kIiwaJoints, extra));
    const RobotConfig rc = loadRobotConfig(file);
    const std::string e = errorOf([&] { WholeBodyModel m(rc); });
    EXPECT_NE(e.find(file), std::string::npos) << e;
    EXPECT_NE(e.find("which is not in the URDF"), std::string::npos) << e;
    const std::string field = extra.find("obstacle_stop") != std::string::npos
                                  ? "robot.obstacle_stop_distances"
                                  : "robot.collision." + extra.substr(extra.find('{') + 1, extra.find(':', extra.find('{')) - extra.find('{') - 1);
    EXPECT_NE(e.find(field), std::string::npos) << field << " not in " << e;
  }
}

// The KUKA's map names the KUKA but sampled the KUKA's joint limits, not the minimal file's:
// the controller does not start on it.
TEST(MinimalRobotYaml, AMapOfAnotherArmIsAStartUpError) {
  const std::string file = writeTemp(minimalYaml(kIiwaJoints, "  name: kuka_iiwa14_kmr\n  reachability_map: " + kConfigDir +
                                                                  "/robots/kuka_iiwa14_kmr/reachability_map.bin\n"));
  ControlCycleParams params = loadControlCycleParams(ehc_common::ConfigNode::loadFile(kConfigDir + "/control/controller.yaml", "test"));
  params.robot_file = file;
  const std::string e = errorOf([&] { ControlCycle cycle(params); });
  EXPECT_NE(e.find("built for another arm"), std::string::npos) << e;
  EXPECT_NE(e.find("joint iiwa_joint_1 has limits [-2.9, 2.9]"), std::string::npos) << e;
  EXPECT_NE(e.find("regenerate it with ehc_reachability"), std::string::npos) << e;
}

TEST(MinimalRobotYaml, ArmsOfSixOrSevenJointsOnly) {
  for (const std::string& joints : {std::string("iiwa_joint_1, iiwa_joint_2, iiwa_joint_3, iiwa_joint_4, iiwa_joint_5"),
                                    kIiwaJoints + ", iiwa_joint_8"}) {
    const std::string file = writeTemp(minimalYaml(joints));
    const std::string e = errorOf([&] { loadRobotConfig(file); });
    EXPECT_NE(e.find(file), std::string::npos) << e;
    EXPECT_NE(e.find("robot.arm.joints"), std::string::npos) << e;
    EXPECT_NE(e.find("6 or 7"), std::string::npos) << e;
  }
}
