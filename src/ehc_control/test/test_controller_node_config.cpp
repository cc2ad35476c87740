// The `node:` section of controller.yaml (ControllerNodeParams): the defaults without one, the
// shipped files (lock-step and the real robot's timer), a bad value that names its field, and
// an unknown key that fails once every loader of the file has run (as ehc_controller_node does).

#include "ehc_common/config_node.h"
#include "ehc_control/control_cycle.h"
#include "ehc_control/controller_node_config.h"
#include "ehc_test/control_fixtures.h"

#include <gtest/gtest.h>

#include <string>

using ehc_common::ConfigNode;

namespace ehc_control {
namespace {

using test::errorOf;

const std::string kConfigDir = EHC_CONFIG_DIR;

ControllerNodeParams load(const std::string& yaml) {
  return loadControllerNodeParams(ConfigNode::loadString(yaml, "controller.yaml", "ControllerNode"));
}

TEST(ControllerNodeParams, DefaultsWithoutANodeSection) {
  const ControllerNodeParams p = load("controller: {}\n");
  const ControllerNodeParams d;
  EXPECT_EQ(p.trigger, CycleTrigger::State);
  EXPECT_EQ(p.rate, d.rate);
  EXPECT_EQ(p.wall_timeout, d.wall_timeout);
  EXPECT_EQ(d.rate, 100.0);
  EXPECT_EQ(d.wall_timeout, 0.5);
  EXPECT_EQ(p.summary(), "trigger state, wall-clock watchdog 0.5 s");
}

TEST(ControllerNodeParams, ReadsTheShippedFiles) {
  const auto sim = loadControllerNodeParams(ConfigNode::loadFile(kConfigDir + "/control/controller.yaml", "ControllerNode"));
  EXPECT_EQ(sim.trigger, CycleTrigger::State);
  const auto robot = loadControllerNodeParams(ConfigNode::loadFile(kConfigDir + "/realman/controller.yaml", "ControllerNode"));
  EXPECT_EQ(robot.trigger, CycleTrigger::Timer);
  EXPECT_EQ(robot.rate, 50.0);
  EXPECT_EQ(robot.summary(), "trigger timer at 50.000000 Hz, wall-clock watchdog 0.5 s");
}

TEST(ControllerNodeParams, ABadValueNamesItsField) {
  EXPECT_NE(errorOf([] { load("node: {trigger: clock}\n"); }).find("field 'node.trigger' must be 'state' or 'timer'"),
            std::string::npos);
  const std::string rate = errorOf([] { load("node: {trigger: timer, rate: 0.5}\n"); });
  EXPECT_NE(rate.find("[ControllerNodeParams] parameter 'node.rate' = 0.5 is outside [1, 1000]"), std::string::npos) << rate;
  EXPECT_NE(rate.find("controller.yaml"), std::string::npos) << rate;
  const std::string wall = errorOf([] { load("node: {wall_timeout: 20}\n"); });
  EXPECT_NE(wall.find("'node.wall_timeout' = 20"), std::string::npos) << wall;
  EXPECT_NE(errorOf([] { load("node: {rate: fast}\n"); }).find("field 'node.rate' has the wrong type"), std::string::npos);
}

TEST(ControllerNodeParams, AnUnknownKeyFailsOnceEveryLoaderHasRun) {
  const ConfigNode root = ConfigNode::loadFile(kConfigDir + "/control/controller.yaml", "ControllerNode");
  loadControlCycleParams(root);
  loadControllerNodeParams(root);
  EXPECT_NO_THROW(root.rejectUnknownKeys());  // the shipped file: every key is read

  const ConfigNode typo = ConfigNode::loadString("node: {trigger: state, wall_timout: 1.0}\n", "controller.yaml", "ControllerNode");
  loadControllerNodeParams(typo);
  const std::string why = errorOf([&] { typo.rejectUnknownKeys(); });
  EXPECT_NE(why.find("unknown field 'node.wall_timout'"), std::string::npos) << why;
  EXPECT_NE(why.find("node.wall_timeout"), std::string::npos) << why;  // the nearest known key
}

}  // namespace
}  // namespace ehc_control
