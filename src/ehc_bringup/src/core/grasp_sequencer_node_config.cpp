#include "ehc_bringup/grasp_sequencer_node_config.h"

#include "ehc_common/config_node.h"
#include "ehc_control/robot_config.h"
#include "ehc_control/whole_body_model.h"

#include <stdexcept>
#include <utility>

namespace ehc_bringup {

void SequencerNodeParams::applyRobotFrames(const ehc_control::WholeBodyModel& model) {
  const ehc_control::RobotConfig& robot = model.config();
  // The frames set in the file are links of the robot's URDF (the robot's own are checked by
  // the model, naming robot.yaml's field).
  for (const auto& [frame, field] : {std::make_pair(&tcp_frame, "node.tcp_frame"), std::make_pair(&camera_frame, "node.camera_frame")})
    if (!frame->empty() && !model.hasLink(*frame))
      throw std::invalid_argument("[SequencerNodeParams] " + source_file + ": field '" + field + "' names link '" + *frame +
                                  "' which is not in the URDF " + robot.urdf_path + " (robot " + robot.source_file + ")");
  if (world_frame.empty()) world_frame = robot.world_frame;
  if (tcp_frame.empty()) tcp_frame = robot.tcp_frame;
  if (camera_frame.empty()) camera_frame = robot.camera_frame;
}

std::string SequencerNodeParams::summary() const {
  std::string s = "  goal -> " + goal_topic + ", object pose -> " + object_pose_topic + ", candidates <- " +
                  candidates_topic + ", status <- " + status_topic + ", gripper <- " + sim_status_topic + " / -> " +
                  gripper_service + "\n  TCP " + world_frame + " -> " + tcp_frame + ", camera " + camera_frame +
                  " (tf) + " + camera_info_topic + " (TfM)\n  pose topics:";
  for (const auto& t : pose_topics) s += " " + t;
  s += "\n  obstacle exclusion (the object while touched) -> " + (exclusion_topic.empty() ? std::string("off") : exclusion_topic);
  s += "\n  target selectors <- " + (target_selector_topic.empty() ? std::string("off") : target_selector_topic) +
       ", current target -> " + current_target_topic + ", cloud target poses <- " + cloud_target_topic;
  return s;
}

SequencerNodeParams loadSequencerNodeParams(const ehc_common::ConfigNode& root) {
  SequencerNodeParams p;
  p.source_file = root.file();
  const auto n = root.childOrEmpty("node");
  p.robot_file = n.has("robot") ? ehc_control::robotFileField(n, "robot") : ehc_control::resolveRobotFile("realman_rm65_water2");
  p.world_frame = n.get("world_frame", p.world_frame);
  p.tcp_frame = n.get("tcp_frame", p.tcp_frame);
  p.camera_frame = n.get("camera_frame", p.camera_frame);
  p.camera_info_topic = n.get("camera_info_topic", p.camera_info_topic);
  p.goal_topic = n.get("goal_topic", p.goal_topic);
  p.object_pose_topic = n.get("object_pose_topic", p.object_pose_topic);
  p.target_centre_topic = n.get("target_centre_topic", p.target_centre_topic);
  p.candidates_topic = n.get("candidates_topic", p.candidates_topic);
  p.status_topic = n.get("status_topic", p.status_topic);
  p.sim_status_topic = n.get("sim_status_topic", p.sim_status_topic);
  p.gripper_service = n.get("gripper_service", p.gripper_service);
  p.exclusion_topic = n.get("exclusion_topic", p.exclusion_topic);
  p.target_selector_topic = n.get("target_selector_topic", p.target_selector_topic);
  p.current_target_topic = n.get("current_target_topic", p.current_target_topic);
  p.cloud_target_topic = n.get("cloud_target_topic", p.cloud_target_topic);
  p.exit_when_done = n.get("exit_when_done", p.exit_when_done);
  for (const char* k : {"world_frame", "tcp_frame", "goal_topic", "status_topic", "gripper_service", "current_target_topic",
                        "cloud_target_topic"})
    if (n.has(k) && n.get<std::string>(k, "").empty()) n.fail(k, "must not be empty");
  for (std::size_t i = 0; i < root.listSize("objects"); ++i) {
    const ehc_common::ConfigNode o = root.element("objects", i);
    p.pose_topics.push_back(o.require<std::string>("pose_topic"));
    if (p.pose_topics.back().empty()) o.fail("pose_topic", "must not be empty");
  }
  return p;
}

}  // namespace ehc_bringup
