#pragma once
// The `node:` section of the grasp sequencer's YAML (config/demo/grasp_sequencer.yaml) and the
// objects' pose topics: what ehc_grasp_sequencer_node connects to. The `sequencer:` section and
// the objects' names and approaches are GraspSequencerParams (grasp_sequencer.h). ROS-free,
// unit-tested.

#include <string>
#include <vector>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_control {
class WholeBodyModel;
}  // namespace ehc_control

namespace ehc_bringup {

struct SequencerNodeParams {
  std::string robot_file;  ///< node.robot (a robot name or a robot.yaml); default the RealMan's
  /// node.world_frame / tcp_frame / camera_frame; "" (not in the file): the robot's
  /// (frames.world / tcp / camera_optical of robot.yaml, applyRobotFrames).
  std::string world_frame, tcp_frame, camera_frame;
  std::string camera_info_topic = "/camera/color/camera_info";
  std::string goal_topic = "/ehc/target_pose";
  std::string object_pose_topic = "/ehc/sequencer/object_pose";
  std::string target_centre_topic = "/ehc/target_centre";  ///< point the controller's camera watches
  std::string candidates_topic = "/ehc/grasp_candidates";
  std::string status_topic = "/ehc/status";
  std::string sim_status_topic = "/sim/status";
  std::string gripper_service = "/sim/gripper";
  std::string exclusion_topic = "/ehc/obstacle_exclusion";  ///< "" = none sent
  /// Targets without tags (ehc_control::TargetSelector, ehc_msgs/TargetSelector): an object's
  /// target is set on target_selector_topic ("" = none: every object's is its tag); the current
  /// object's goes out on current_target_topic (latched, the grasp node's selector), and a cloud
  /// target's poses come from the grasp node on cloud_target_topic.
  std::string target_selector_topic = "/ehc/target_selector";
  std::string current_target_topic = "/ehc/sequencer/target_selector";
  std::string cloud_target_topic = "/ehc/perception/cloud_target";
  std::vector<std::string> pose_topics;  ///< per object (objects[i].pose_topic)
  bool exit_when_done = true;

  std::string source_file;  ///< the YAML it was loaded from (for errors)

  /// Sets the frames the file left empty to the robot's (`model`: robot.yaml checked against
  /// its URDF). Throws std::invalid_argument naming the file and the field when node.tcp_frame
  /// or node.camera_frame is not a link of the robot's URDF.
  void applyRobotFrames(const ehc_control::WholeBodyModel& model);
  std::string summary() const;
};

/// Reads `node:` and every `objects[i].pose_topic` of the sequencer's YAML (`root`). Throws
/// std::invalid_argument naming the file and the field: a frame, goal_topic, status_topic or
/// gripper_service set empty, an object without a pose_topic or with an empty one. Keys it does
/// not know stay unread, so the caller's rejectUnknownKeys() on `root` reports them.
SequencerNodeParams loadSequencerNodeParams(const ehc_common::ConfigNode& root);

}  // namespace ehc_bringup
