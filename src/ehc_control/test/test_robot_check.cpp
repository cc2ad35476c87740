// RobotCheck (`ehc_kinematics --check`): every robot folder under config/robots and the 7-DOF
// test robot pass every check; one broken copy of a robot folder (in a temporary folder) per
// check fails it with a line that names the check and what is wrong, while the checks it does
// not touch stay ok.

#include "ehc_control/reachability_map.h"
#include "ehc_control/robot_check.h"
#include "ehc_control/robot_config.h"
#include "ehc_test/temp_dir.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

using namespace ehc_control;

namespace {

const std::string kFixture = std::string(EHC_TEST_FIXTURES_DIR) + "/robots/arm7_differential";

/// A copy of a robot folder in a fresh temporary folder, to break.
struct RobotCopy {
  explicit RobotCopy(const std::string& from = kFixture) : folder(dir.path + "/robot") { ehc_test::copyFolder(from, folder); }
  std::string yaml() const { return folder + "/robot.yaml"; }
  std::string urdf() const { return folder + "/robot.urdf"; }
  std::vector<RobotCheckLine> check() const { return checkRobot(yaml()); }
  ehc_test::TempDir dir{"ehc_robot_check"};
  std::string folder;
};

std::string text(const std::vector<RobotCheckLine>& lines) {
  std::string s;
  for (const auto& l : lines) s += toString(l) + "\n";
  return s;
}

std::vector<RobotCheckLine> problems(const std::vector<RobotCheckLine>& lines) {
  std::vector<RobotCheckLine> p;
  std::copy_if(lines.begin(), lines.end(), std::back_inserter(p), [](const RobotCheckLine& l) { return !l.ok; });
  return p;
}

/// A problem line of `check` contains every fragment.
void expectProblem(const std::vector<RobotCheckLine>& lines, const std::string& check,
                   const std::vector<std::string>& fragments) {
  const auto it = std::find_if(lines.begin(), lines.end(), [&](const RobotCheckLine& l) {
    return !l.ok && l.check == check &&
           std::all_of(fragments.begin(), fragments.end(), [&](const std::string& f) { return l.message.find(f) != std::string::npos; });
  });
  EXPECT_NE(it, lines.end()) << "no '" << check << "' problem with the expected text in:\n" << text(lines);
}

/// Exactly one problem, of `check`, containing every fragment.
void expectOnlyProblem(const std::vector<RobotCheckLine>& lines, const std::string& check,
                       const std::vector<std::string>& fragments) {
  EXPECT_EQ(problems(lines).size(), 1u) << text(lines);
  expectProblem(lines, check, fragments);
}

bool hasOk(const std::vector<RobotCheckLine>& lines, const std::string& check) {
  return std::any_of(lines.begin(), lines.end(), [&](const RobotCheckLine& l) { return l.ok && l.check == check; });
}

const std::vector<std::string> kAllChecks = {"robot.yaml", "frames", "arm joints", "joint limits", "camera mount",
                                             "fingers", "camera view", "reachability map"};

}  // namespace

TEST(RobotCheck, EveryShippedRobotAndTheTestRobotPassEveryCheck) {
  std::vector<std::string> files;
  for (const std::string& name : robotNames()) files.push_back(resolveRobotFile(name));
  ASSERT_GE(files.size(), 4u) << "config/robots holds the RealMan, the KUKA, the Kinova and the UR5e";
  files.push_back(kFixture + "/robot.yaml");
  for (const std::string& file : files) {
    const auto lines = checkRobot(file);
    EXPECT_TRUE(allOk(lines)) << file << ":\n" << text(lines);
    for (const std::string& check : kAllChecks) EXPECT_TRUE(hasOk(lines, check)) << file << ": " << check << "\n" << text(lines);
  }
}

TEST(RobotCheck, AMissingVelocityLimitIsARobotYamlProblemNamingTheField) {
  RobotCopy c;
  ehc_test::replaceInFile(c.yaml(), "    velocity: [", "    # velocity: [");
  expectOnlyProblem(c.check(), "robot.yaml", {"robot.arm.velocity", c.yaml()});
}

TEST(RobotCheck, AnUnparsableUrdf) {
  RobotCopy c;
  ehc_test::replaceInFile(c.urdf(), "<robot name=", "<robt name=");
  expectOnlyProblem(c.check(), "urdf", {"does not parse", c.urdf()});
}

TEST(RobotCheck, FramesTheUrdfLacksOneLineEach) {
  RobotCopy c;
  ehc_test::replaceInFile(c.yaml(), "tcp: ee_link", "tcp: ee_lnk");
  ehc_test::replaceInFile(c.yaml(), "camera_optical: camera_color_optical_frame", "camera_optical: camera_optical_frame");
  const auto lines = c.check();
  EXPECT_EQ(problems(lines).size(), 2u) << text(lines);
  expectProblem(lines, "frames", {"robot.frames.tcp names link 'ee_lnk'", "not in the URDF"});
  expectProblem(lines, "frames", {"robot.frames.camera_optical names link 'camera_optical_frame'"});
}

TEST(RobotCheck, ACameraMountJointTheUrdfLacks) {
  RobotCopy c;
  ehc_test::replaceInFile(c.yaml(), "  frames:", "  calibration:\n    camera: {joint: camera_joint, xyz: [0, 0, 0], rpy: [0, 0, 0]}\n  frames:");
  expectOnlyProblem(c.check(), "frames", {"robot.calibration names joint 'camera_joint'"});
}

TEST(RobotCheck, AnArmJointTheUrdfLacks) {
  RobotCopy c;
  ehc_test::replaceInFile(c.yaml(), "joint3, joint4", "joint3, joint_4");
  expectOnlyProblem(c.check(), "arm joints", {"robot.arm.joints names joint 'joint_4'"});
}

TEST(RobotCheck, ArmJointsOutOfOrder) {
  RobotCopy c;
  ehc_test::replaceInFile(c.yaml(), "[joint1, joint2, joint3", "[joint3, joint2, joint1");
  expectProblem(c.check(), "arm joints", {"in order", "joint1, joint2, joint3, joint4"});
}

TEST(RobotCheck, AnAbsurdVelocityLimit) {
  RobotCopy c;  // 85 deg/s written as if it were rad/s
  ehc_test::replaceInFile(c.yaml(), "velocity: [1.4835,", "velocity: [85.0,");
  ehc_test::replaceInFile(c.urdf(), "velocity=\"1.4835\"", "velocity=\"85\"");
  expectOnlyProblem(c.check(), "joint limits", {"joint joint1: velocity 85.000 rad/s", "plausible"});
}

TEST(RobotCheck, AJointRangeOfMoreThanTwoTurnsEitherWay) {
  RobotCopy c(configDirectory() + "/robots/kinova_gen3_husky");  // continuous joints: no URDF limit
  ehc_test::replaceInFile(c.yaml(), "lower:    [-6.283185307179586,", "lower:    [-20.0,");
  // The map sampled the old limits: that is found too.
  const auto lines = c.check();
  expectProblem(lines, "joint limits", {"joint gen3_joint_1: range [-20.000", "two turns"});
  expectProblem(lines, "reachability map", {"the map sampled"});
  EXPECT_EQ(problems(lines).size(), 2u) << text(lines);
}

TEST(RobotCheck, AReadyPoseAtAJointLimit) {
  RobotCopy c;
  ehc_test::replaceInFile(c.yaml(), "ready:    [0.0, 0.5,", "ready:    [0.0, 2.05,");
  expectProblem(c.check(), "ready pose", {"joint joint2 is 0.044 rad from its limit", "joint stop"});
}

TEST(RobotCheck, ACameraOnTheBaseIsNotOnTheHand) {
  RobotCopy c;
  ehc_test::replaceInFile(c.urdf(), "<parent link=\"link7\"/>\n    <child link=\"camera_link\"/>",
                          "<parent link=\"base_link\"/>\n    <child link=\"camera_link\"/>");
  expectProblem(c.check(), "camera mount", {"does not move with the last arm joint 'joint7'"});
}

TEST(RobotCheck, FingerJointsMissingOrUnequal) {
  {
    RobotCopy c;
    ehc_test::replaceInFile(c.urdf(), "<joint name=\"right_finger_joint\" type=\"prismatic\">",
                            "<joint name=\"right_finger_joint\" type=\"fixed\">");
    expectOnlyProblem(c.check(), "fingers", {"exactly two prismatic finger joints (found 1: left_finger_joint)"});
  }
  {
    RobotCopy c;
    ehc_test::replaceInFile(c.urdf(), "<joint name=\"left_finger_joint\" type=\"prismatic\">",
                            "<joint name=\"left_finger_joint\" type=\"fixed\">");
    ehc_test::replaceInFile(c.urdf(), "<joint name=\"right_finger_joint\" type=\"prismatic\">",
                            "<joint name=\"right_finger_joint\" type=\"fixed\">");
    expectOnlyProblem(c.check(), "fingers", {"(found 0)"});
  }
  {
    RobotCopy c;
    ehc_test::replaceInFile(c.urdf(), "<limit lower=\"0\" upper=\"0.035\" effort=\"15\" velocity=\"0.05\"/>\n    <mimic",
                            "<limit lower=\"0\" upper=\"0.03\" effort=\"15\" velocity=\"0.05\"/>\n    <mimic");
    expectOnlyProblem(c.check(), "fingers", {"right_finger_joint", "same travel"});
  }
}

TEST(RobotCheck, FingerPadsApartWhenClosedOrOnOneSide) {
  {
    // The joint off the centre line, the finger reaching outward from it: the pads stay 10 mm
    // apart when closed.
    RobotCopy c;
    ehc_test::replaceInFile(c.urdf(), "<child link=\"left_finger_link\"/>\n    <origin xyz=\"0 0 0.08\"",
                            "<child link=\"left_finger_link\"/>\n    <origin xyz=\"0 0.005 0.08\"");
    expectOnlyProblem(c.check(), "fingers", {"left_finger_link", "pad lies 0.0050 m from the TCP"});
  }
  {
    // The left finger's box reaching inward: across the closing axis when closed.
    RobotCopy c;
    ehc_test::replaceInFile(c.urdf(), "<origin xyz=\"0 0.005 0.025\" rpy=\"0 0 0\"/>\n      <geometry>",
                            "<origin xyz=\"0 -0.002 0.025\" rpy=\"0 0 0\"/>\n      <geometry>");
    expectOnlyProblem(c.check(), "fingers", {"left_finger_link", "reaches across the TCP's closing axis"});
  }
  {
    // The pads beyond the TCP: the fingers end 5 mm short of its depth.
    RobotCopy c;
    ehc_test::replaceInFile(c.urdf(), "<child link=\"left_finger_link\"/>\n    <origin xyz=\"0 0 0.08\"",
                            "<child link=\"left_finger_link\"/>\n    <origin xyz=\"0 0 0.055\"");
    expectOnlyProblem(c.check(), "fingers", {"left_finger_link", "must reach the TCP's depth"});
  }
}

TEST(RobotCheck, AMeshCollisionShape) {
  RobotCopy c;
  ehc_test::replaceInFile(c.urdf(), "<geometry><cylinder radius=\"0.07\" length=\"0.15\"/></geometry>",
                          "<geometry><mesh filename=\"package://arm/base.stl\"/></geometry>");
  expectOnlyProblem(c.check(), "collision geometry", {"mesh"});
}

TEST(RobotCheck, AReadyPoseWhoseCameraLooksAwayFromTheScene) {
  RobotCopy c;  // the arm turned to the left: the camera looks sideways
  ehc_test::replaceInFile(c.yaml(), "ready:    [0.0, 0.5,", "ready:    [1.5, 0.5,");
  expectOnlyProblem(c.check(), "camera view", {"86 deg left of ahead", "8 of 8 corners", "will not see the scene",
                                               "robot.arm.ready"});
  // The same robot sees a region that lies where its camera looks.
  RobotCheckParams p;
  p.view_min = Eigen::Vector3d(-0.1, 1.4, 0.75);
  p.view_max = Eigen::Vector3d(0.25, 1.7, 0.85);
  EXPECT_TRUE(hasOk(checkRobot(c.yaml(), p), "camera view")) << text(checkRobot(c.yaml(), p));
}

TEST(RobotCheck, AMapOfAnotherArm) {
  RobotCopy c;  // the forearm 4 cm longer than the arm the map was built for
  ehc_test::replaceInFile(c.urdf(), "<origin xyz=\"0 0 0.2155\" rpy=\"0 0 0\"/>\n    <axis xyz=\"0 -1 0\"/>",
                          "<origin xyz=\"0 0 0.2555\" rpy=\"0 0 0\"/>\n    <axis xyz=\"0 -1 0\"/>");
  expectOnlyProblem(c.check(), "reachability map", {"built for another arm", "the TCP at reference configuration",
                                                    "rebuild it: rosrun ehc_control ehc_reachability", "--samples 3000000"});
}

TEST(RobotCheck, AMapOfOtherJointLimits) {
  RobotCopy c;
  ehc_test::replaceInFile(c.yaml(), "upper:    [ 2.9670597283903604,  2.0943951023931953,", "upper:    [ 2.9670597283903604,  2.0,");
  expectOnlyProblem(c.check(), "reachability map", {"joint joint2 has limits [-2.0944, 2]", "the map sampled [-2.0944, 2.0944]"});
}

TEST(RobotCheck, AMapOfAnotherRobotNoMapAndAMapOfTheFirstFormat) {
  {
    RobotCopy c;
    ehc_test::replaceInFile(c.yaml(), "reachability_map: reachability_map.bin",
                            "reachability_map: " + configDirectory() + "/robots/kuka_iiwa14_kmr/reachability_map.bin");
    expectOnlyProblem(c.check(), "reachability map", {"map was built for robot 'kuka_iiwa14_kmr'"});
  }
  {
    RobotCopy c;
    ehc_test::replaceInFile(c.yaml(), "  reachability_map: reachability_map.bin", "");
    expectOnlyProblem(c.check(), "reachability map", {"names none", "ehc_reachability"});
  }
  {
    RobotCopy c;  // the map as the first format wrote it: no limits, no reference poses
    const std::string map = c.folder + "/reachability_map.bin";
    std::string bytes = ehc_test::readText(map);
    const auto limits = bytes.find("\nlimits "), data = bytes.find("\ndata\n");
    ASSERT_NE(limits, std::string::npos);
    bytes = "EHC_REACHABILITY_MAP 1" + bytes.substr(bytes.find('\n'), limits - bytes.find('\n')) + bytes.substr(data);
    std::ofstream(map, std::ios::binary | std::ios::trunc) << bytes;
    EXPECT_FALSE(ReachabilityMap::load(map).hasKinematics());
    expectOnlyProblem(c.check(), "reachability map", {"records no kinematics", "rebuild it"});
  }
}

TEST(RobotCheck, AnUnreadableRobotYamlIsOneProblem) {
  const auto lines = checkRobot("/nonexistent/robot.yaml");
  expectOnlyProblem(lines, "robot.yaml", {"/nonexistent/robot.yaml"});
  EXPECT_EQ(lines.size(), 1u);
}

TEST(RobotCheck, InvalidParamsThrow) {
  RobotCheckParams p;
  p.view_min.x() = 3.0;  // min > max
  EXPECT_THROW(checkRobot(kFixture + "/robot.yaml", p), std::invalid_argument);
  p = RobotCheckParams{};
  p.view_max_distance = std::nan("");
  EXPECT_THROW(checkRobot(kFixture + "/robot.yaml", p), std::invalid_argument);
}
