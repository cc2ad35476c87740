// The grasp sequencer node's parameters (SequencerNodeParams): the shipped demo file loads with
// every key read; the defaults and the robot's frames for what the file leaves out; a bad value
// names its field; an unknown key fails once every loader has run (as the node does).

#include "ehc_bringup/grasp_sequencer.h"
#include "ehc_bringup/grasp_sequencer_node_config.h"
#include "ehc_common/config_node.h"
#include "ehc_control/robot_config.h"
#include "ehc_control/whole_body_model.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

using ehc_common::ConfigNode;

using ehc_bringup::SequencerNodeParams;

namespace {

const std::string kConfigDir = EHC_CONFIG_DIR;

std::string errorOf(const std::string& yaml) {
  try {
    ehc_bringup::loadSequencerNodeParams(ConfigNode::loadString(yaml, "seq.yaml", "GraspSequencerNode"));
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(SequencerNodeParams, TheShippedDemoFileLoadsWithEveryKeyRead) {
  const ConfigNode root = ConfigNode::loadFile(kConfigDir + "/demo/grasp_sequencer.yaml", "GraspSequencerNode");
  const SequencerNodeParams p = ehc_bringup::loadSequencerNodeParams(root);
  ehc_bringup::loadGraspSequencerParams(root);
  EXPECT_NO_THROW(root.rejectUnknownKeys());
  EXPECT_EQ(p.robot_file, ehc_control::resolveRobotFile("realman_rm65_water2"));
  ASSERT_EQ(p.pose_topics.size(), 3u);
  EXPECT_EQ(p.pose_topics[0], "/ehc/perception/front/target_pose");
  EXPECT_EQ(p.exclusion_topic, "/ehc/obstacle_exclusion");
  EXPECT_TRUE(p.exit_when_done);
}

TEST(SequencerNodeParams, DefaultsAndTheRobotsFrames) {
  const ConfigNode root = ConfigNode::loadString("objects: [{name: a, pose_topic: /a}]\n", "seq.yaml", "GraspSequencerNode");
  SequencerNodeParams p = ehc_bringup::loadSequencerNodeParams(root);
  const SequencerNodeParams d;
  EXPECT_EQ(p.robot_file, ehc_control::resolveRobotFile("realman_rm65_water2"));
  EXPECT_EQ(p.goal_topic, d.goal_topic);
  EXPECT_EQ(p.status_topic, "/ehc/status");
  EXPECT_EQ(p.gripper_service, "/sim/gripper");
  EXPECT_EQ(p.pose_topics, std::vector<std::string>{"/a"});
  EXPECT_TRUE(p.world_frame.empty());  // not in the file: the robot's
  const ehc_control::WholeBodyModel kuka(ehc_control::loadRobotConfig(ehc_control::resolveRobotFile("kuka_iiwa14_kmr")));
  p.tcp_frame = "gripper_base_link";  // set in the file: kept
  p.applyRobotFrames(kuka);
  EXPECT_EQ(p.world_frame, kuka.config().world_frame);
  EXPECT_EQ(p.camera_frame, kuka.config().camera_frame);
  EXPECT_EQ(p.tcp_frame, "gripper_base_link");
  EXPECT_NE(p.summary().find("pose topics: /a"), std::string::npos) << p.summary();
}

TEST(SequencerNodeParams, FramesThatAreNotLinksOfTheRobotAreStartUpErrorsNamingTheField) {
  const ehc_control::WholeBodyModel kuka(ehc_control::loadRobotConfig(ehc_control::resolveRobotFile("kuka_iiwa14_kmr")));
  for (const std::string field : {"tcp_frame", "camera_frame"}) {
    SequencerNodeParams p = ehc_bringup::loadSequencerNodeParams(ConfigNode::loadString(
        "node: {" + field + ": no_such_link}\nobjects: [{name: a, pose_topic: /a}]\n", "seq.yaml", "GraspSequencerNode"));
    try {
      p.applyRobotFrames(kuka);
      FAIL() << field << " accepted";
    } catch (const std::invalid_argument& e) {
      const std::string w = e.what();
      EXPECT_NE(w.find("seq.yaml: field 'node." + field + "' names link 'no_such_link' which is not in the URDF"),
                std::string::npos) << w;
    }
  }
}

TEST(SequencerNodeParams, ABadValueNamesItsField) {
  EXPECT_NE(errorOf("node: {goal_topic: ''}\n").find("field 'node.goal_topic' must not be empty"), std::string::npos);
  EXPECT_NE(errorOf("node: {world_frame: ''}\n").find("field 'node.world_frame' must not be empty"), std::string::npos);
  EXPECT_NE(errorOf("node: {exit_when_done: sometimes}\n").find("field 'node.exit_when_done' has the wrong type"),
            std::string::npos);
  EXPECT_NE(errorOf("objects: [{name: a, pose_topic: /a}, {name: b}]\n").find("objects[1].pose_topic"), std::string::npos);
  EXPECT_NE(errorOf("objects: [{name: a, pose_topic: ''}]\n").find("field 'objects[0].pose_topic' must not be empty"),
            std::string::npos);
  EXPECT_NE(errorOf("node: {robot: no_such_robot}\n"), "");
  EXPECT_NE(errorOf("node: {current_target_topic: ''}\n").find("field 'node.current_target_topic' must not be empty"),
            std::string::npos);
  EXPECT_NE(errorOf("node: {cloud_target_topic: ''}\n").find("field 'node.cloud_target_topic' must not be empty"),
            std::string::npos);
}

TEST(SequencerNodeParams, AnUnknownKeyFailsOnceEveryLoaderHasRun) {
  const ConfigNode root = ConfigNode::loadString(
      "node: {goal_topc: /x}\nobjects: [{name: a, approach: forward, pose_topic: /a}]\n", "seq.yaml", "GraspSequencerNode");
  ehc_bringup::loadSequencerNodeParams(root);
  ehc_bringup::loadGraspSequencerParams(root);
  try {
    root.rejectUnknownKeys();
    FAIL() << "a misspelt key was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("unknown field 'node.goal_topc'"), std::string::npos) << e.what();
  }
}

}  // namespace
