// loadRobotConfig: the shipped robot.yaml loads; bad files fail with a message naming the field.

#include "ehc_common/config_node.h"
#include "ehc_control/robot_config.h"
#include "ehc_test/control_fixtures.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <regex>

using ehc_common::ConfigNode;

using namespace ehc_control;

namespace {

/// Writes the shipped robot.yaml with one textual substitution to a temp file.
std::string variant(const std::string& from, const std::string& to) {
  std::ifstream in(test::realmanYaml());
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto pos = text.find(from);
  if (pos == std::string::npos) throw std::runtime_error("pattern not in robot.yaml: " + from);
  text.replace(pos, from.size(), to);
  // Keep the URDF reference valid from the temp folder.
  const std::string urdf = std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/robot.urdf";
  text = std::regex_replace(text, std::regex("urdf: robot.urdf"), "urdf: " + urdf);
  char name[] = "/tmp/ehc_robot_XXXXXX.yaml";
  const int fd = mkstemps(name, 5);
  if (fd < 0) throw std::runtime_error("mkstemps failed");
  close(fd);
  std::ofstream(name) << text;
  return name;
}

void expectLoadError(const std::string& path, const std::string& needle) {
  try {
    loadRobotConfig(path);
    FAIL() << "no exception for " << needle;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("[RobotConfig]", 0), 0u) << e.what();
  }
}

}  // namespace

TEST(RobotConfig, ShippedRealmanConfigLoads) {
  const RobotConfig c = loadRobotConfig(test::realmanYaml());
  EXPECT_EQ(c.name, "realman_rm65_water2");
  EXPECT_EQ(c.base_type, BaseType::Differential);
  EXPECT_EQ(c.nArm(), 6);
  EXPECT_DOUBLE_EQ(c.max_linear_velocity, 0.5);
  EXPECT_DOUBLE_EQ(c.max_angular_velocity, 1.0);
  EXPECT_NEAR(c.arm_upper[0], 178.0 * M_PI / 180.0, 1e-15);
  EXPECT_NEAR(c.arm_upper[4], 128.0 * M_PI / 180.0, 1e-15);
  EXPECT_EQ(c.velocityLimits().size(), 8);
  EXPECT_EQ(c.calibration.size(), 2u);
  EXPECT_NE(c.summary().find("joint6"), std::string::npos);
}

TEST(RobotConfig, MissingFile) { expectLoadError("/nonexistent/robot.yaml", "cannot read config file"); }

TEST(RobotConfig, BadBaseType) {
  expectLoadError(variant("type: differential", "type: tracked"), "field 'robot.base.type'");
}

TEST(RobotConfig, WrongLimitCount) {
  expectLoadError(variant("velocity:  [3.14, 3.14, 3.92, 3.92, 3.92, 3.92]", "velocity: [3.14]"),
                  "field 'robot.arm.velocity' must have 6 elements");
}

TEST(RobotConfig, NonFiniteValue) {
  expectLoadError(variant("max_linear_velocity: 0.5", "max_linear_velocity: .nan"),
                  "field 'robot.base.max_linear_velocity' must be a finite number");
}

TEST(RobotConfig, OutOfRangeVelocity) {
  expectLoadError(variant("max_linear_velocity: 0.5", "max_linear_velocity: -1"),
                  "robot.base.max_linear_velocity");
}

TEST(RobotConfig, ReadyPoseOutsideLimits) {
  expectLoadError(variant("ready:     [0.0, 0.5", "ready:     [0.0, 3.0"), "robot.arm.ready");
}

TEST(RobotConfig, MissingUrdfField) {
  expectLoadError(variant("urdf: robot.urdf", "urdf_file: robot.urdf"), "field 'robot.urdf' is missing");
}

TEST(RobotConfig, YamlSyntaxError) {
  expectLoadError(variant("robot:\n", "robot: [\n"), "YAML syntax error");
}

TEST(ConfigNode, ExtendsMergesOverTheBaseFile) {
  std::ofstream("/tmp/ehc_base.yaml") << "a: {x: 1, y: 2, list: [1, 2, 3]}\nb: base\n";
  std::ofstream("/tmp/ehc_over.yaml") << "extends: ehc_base.yaml\na: {y: 20, list: [9]}\nc: new\n";
  const auto n = ConfigNode::loadFile("/tmp/ehc_over.yaml", "Test");
  EXPECT_EQ(n.child("a").require<int>("x"), 1);    // kept from the base
  EXPECT_EQ(n.child("a").require<int>("y"), 20);   // overridden
  EXPECT_EQ(n.child("a").requireVector("list").size(), 1);  // lists are replaced
  EXPECT_EQ(n.require<std::string>("b"), "base");
  EXPECT_EQ(n.require<std::string>("c"), "new");
  EXPECT_FALSE(n.has("extends"));
  std::ofstream("/tmp/ehc_loop.yaml") << "extends: ehc_loop.yaml\n";
  EXPECT_THROW(ConfigNode::loadFile("/tmp/ehc_loop.yaml", "Test"), std::invalid_argument);
  std::ofstream("/tmp/ehc_missing.yaml") << "extends: no_such_file.yaml\n";
  try {
    ConfigNode::loadFile("/tmp/ehc_missing.yaml", "Test");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cannot read config file '/tmp/no_such_file.yaml'"), std::string::npos) << e.what();
  }
}

TEST(ConfigNode, RealmanControllerConfigIsTheSimConfigWithATimer) {
  const auto real = ConfigNode::loadFile(std::string(EHC_CONFIG_DIR) + "/realman/controller.yaml", "Test");
  const auto sim = ConfigNode::loadFile(std::string(EHC_CONFIG_DIR) + "/control/controller.yaml", "Test");
  EXPECT_EQ(real.child("node").require<std::string>("trigger"), "timer");
  EXPECT_EQ(sim.child("node").require<std::string>("trigger"), "state");
  // Everything else comes from the same file: the controller tuning cannot drift apart.
  for (const char* section : {"controller", "weighting", "servo"}) {
    std::ostringstream a, b;
    a << real.child(section).yaml();
    b << sim.child(section).yaml();
    EXPECT_EQ(a.str(), b.str()) << section;
  }
  // ... and both stop without obstacle distances (obstacle sensing required: safe by default).
  EXPECT_TRUE(real.child("watchdog").require<bool>("require_obstacles"));
  EXPECT_TRUE(sim.child("watchdog").require<bool>("require_obstacles"));
  for (const char* key : {"state_timeout", "target_timeout", "obstacle_timeout"})
    EXPECT_EQ(real.child("watchdog").require<double>(key), sim.child("watchdog").require<double>(key)) << key;
}

TEST(RobotConfig, MisspelledKeyIsAStartUpError) {
  const std::string path = ::testing::TempDir() + "/typo_robot.yaml";
  {
    std::ofstream f(path);
    f << "robot:\n  urdf: " EHC_CONFIG_DIR "/robots/realman_rm65_water2/robot.urdf\n"
      << "  base: {type: differential, max_linear_velocty: 0.2}\n"
      << "  arm: {joints: [joint1, joint2, joint3, joint4, joint5, joint6], lower: [-3, -2, -2, -3, -2, -6],"
      << " upper: [3, 2, 2, 3, 2, 6], velocity: [3, 3, 3, 3, 3, 3]}\n";
  }
  try {
    ehc_control::loadRobotConfig(path);
    FAIL() << "a misspelled key was silently ignored";
  } catch (const std::invalid_argument& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("typo_robot.yaml"), std::string::npos) << w;
    EXPECT_NE(w.find("did you mean 'robot.base.max_linear_velocity'"), std::string::npos) << w;
  }
}
