#include "ehc_perception/node_config.h"

#include "ehc_common/config_node.h"
#include "ehc_control/robot_config.h"

#include <stdexcept>

using ehc_common::ConfigNode;
using ehc_common::requireRange;

namespace ehc_perception {

// ---------------------------------------------------------------- ehc_tag_node

void TagNodeConfig::validate() const {
  const char* o = "TagNodeConfig";
  requireRange(o, "node.tf_timeout", tf_timeout, 0.0, 5.0);
  requireRange(o, "node.stale_after", stale_after, 0.01, 10.0);
  requireRange(o, "node.max_image_pixels", max_image_pixels, 1, 100000000);
  if (world_frame.empty())
    throw std::invalid_argument(std::string("[") + o + "] parameter 'node.world_frame' must not be empty");
  detector.validate();
  target.validate();
}

std::string TagNodeConfig::summary() const {
  return "ehc_tag_node: image " + image_topic + ", camera_info " +
         (camera_file.empty() ? camera_info_topic : camera_file) + " -> " + target_topic + " in '" +
         world_frame + "' (camera frame '" + (camera_frame.empty() ? "<image header>" : camera_frame) +
         "', tf timeout " + std::to_string(tf_timeout) + " wall s, the newest image only, stale after " +
         std::to_string(stale_after) + " s, at most " + std::to_string(max_image_pixels) + " pixels)\n  " +
         detector.summary() + "\n  " + target.summary();
}

std::vector<std::string> TagNodeConfig::lockstepInputs() const {
  std::vector<std::string> in{image_topic, "/tf"};
  if (camera_file.empty()) in.push_back(camera_info_topic);
  return in;
}

TagNodeConfig loadTagNodeConfig(const std::string& path) {
  const auto root = ConfigNode::loadFile(path, "TagNodeConfig");
  TagNodeConfig c;
  const auto n = root.childOrEmpty("node");
  c.image_topic = n.get("image_topic", c.image_topic);
  c.camera_info_topic = n.get("camera_info_topic", c.camera_info_topic);
  c.target_topic = n.get("target_topic", c.target_topic);
  c.world_frame = n.get("world_frame", c.world_frame);
  c.camera_frame = n.get("camera_frame", c.camera_frame);
  c.camera_file = n.get("camera_file", c.camera_file);
  if (!c.camera_file.empty()) c.camera_file = n.requirePath("camera_file");
  c.tf_timeout = n.get("tf_timeout", c.tf_timeout);
  c.stale_after = n.get("stale_after", c.stale_after);
  c.max_image_pixels = n.get("max_image_pixels", c.max_image_pixels);
  n.validate(c);  // the node fields (the sections below validate themselves as they load)
  c.detector = loadTagDetectorConfig(root.childOrEmpty("tag_detector"));
  c.target = loadTagTargetConfig(root.childOrEmpty("target"));
  root.rejectUnknownKeys();  // a key no loader read is a misspelling
  return c;
}

// ---------------------------------------------------------------- ehc_grasp_node

void GraspNodeConfig::validate() const {
  const char* o = "GraspNodeConfig";
  requireRange(o, "node.tf_timeout", tf_timeout, 0.0, 5.0);
  requireRange(o, "node.stale_after", stale_after, 0.01, 10.0);
  targeting.validate();
  generator.validate();
}

std::string GraspNodeConfig::summary() const {
  return "ehc_grasp_node: " + cloud_topic + " -> " + output_topic + " in '" + world_frame + "', target " +
         (target_topic.empty() ? std::string("<none>") : target_topic) + ", target selector " +
         (selector_topic.empty() ? std::string("<none>") : selector_topic + " (cloud target -> " + cloud_target_topic + ")") +
         ", " + targeting.summary() + ", " +
         "the newest cloud only, stale after " + std::to_string(stale_after) + " s, camera pose waited for " +
         std::to_string(tf_timeout) +
         " wall s\n  " + generator.summary();
}

std::vector<std::string> GraspNodeConfig::lockstepInputs() const {
  return target_topic.empty() ? std::vector<std::string>{cloud_topic, "/tf"}
                              : std::vector<std::string>{cloud_topic, target_topic, "/tf"};
}

GraspNodeConfig loadGraspNodeConfig(const std::string& path) {
  const auto root = ConfigNode::loadFile(path, "GraspNodeConfig");
  GraspNodeConfig c;
  const auto n = root.childOrEmpty("node");
  c.cloud_topic = n.get("cloud_topic", c.cloud_topic);
  c.target_topic = n.get("target_topic", c.target_topic);
  c.output_topic = n.get("output_topic", c.output_topic);
  c.selector_topic = n.get("selector_topic", c.selector_topic);
  c.cloud_target_topic = n.get("cloud_target_topic", c.cloud_target_topic);
  if (!c.selector_topic.empty() && c.cloud_target_topic.empty())
    n.fail("cloud_target_topic", "must not be empty while selector_topic is set");
  c.world_frame = n.get("world_frame", c.world_frame);
  c.targeting = loadGraspTargetingParams(n);
  c.tf_timeout = n.get("tf_timeout", c.tf_timeout);
  c.stale_after = n.get("stale_after", c.stale_after);
  n.validate(c);
  c.generator = loadGraspGeneratorConfig(root.childOrEmpty("grasp_generator"));
  root.rejectUnknownKeys();  // a key no loader read is a misspelling
  return c;
}

// ---------------------------------------------------------------- ehc_obstacle_node

void ObstacleNodeConfig::validate() const {
  const char* o = "ObstacleNodeConfig";
  requireRange(o, "node.publish_rate_hz", publish_rate_hz, 0.1, 1000.0);
  requireRange(o, "node.tf_timeout", tf_timeout, 0.0, 5.0);
  requireRange(o, "node.stale_after", stale_after, 0.01, 10.0);
  monitor.validate();
  map.validate();
}

std::string ObstacleNodeConfig::summary() const {
  return "ehc_obstacle_node: robot " + robot_config + ", " + cloud_topic + " + " + joint_states_topic + " + " +
         odom_topic + " -> " + output_topic + " at " + std::to_string(publish_rate_hz) + " Hz in '" + world_frame +
         "', exclusions " + (exclusion_topic.empty() ? std::string("off") : exclusion_topic) +
         ", clouds stale after " + std::to_string(stale_after) + " s\n  " +
         monitor.summary() + "\n  " + map.summary();
}

std::vector<std::string> ObstacleNodeConfig::lockstepInputs() const {
  std::vector<std::string> in{cloud_topic, joint_states_topic, odom_topic, "/tf"};
  if (!exclusion_topic.empty()) in.push_back(exclusion_topic);
  return in;
}

ObstacleNodeConfig loadObstacleNodeConfig(const std::string& path) {
  const auto root = ConfigNode::loadFile(path, "ObstacleNodeConfig");
  ObstacleNodeConfig c;
  const auto n = root.child("node");
  c.robot_config = ehc_control::robotFileField(n, "robot_config");  // a robot name or a robot.yaml path
  c.cloud_topic = n.get("cloud_topic", c.cloud_topic);
  c.joint_states_topic = n.get("joint_states_topic", c.joint_states_topic);
  c.odom_topic = n.get("odom_topic", c.odom_topic);
  c.output_topic = n.get("output_topic", c.output_topic);
  c.exclusion_topic = n.get("exclusion_topic", c.exclusion_topic);
  c.world_frame = n.get("world_frame", c.world_frame);
  c.publish_rate_hz = n.get("publish_rate_hz", c.publish_rate_hz);
  c.tf_timeout = n.get("tf_timeout", c.tf_timeout);
  c.stale_after = n.get("stale_after", c.stale_after);
  n.validate(c);
  c.monitor = loadObstacleMonitorParams(n);
  c.map = loadObstacleMapConfig(root.childOrEmpty("obstacle_map"));
  root.rejectUnknownKeys();  // a key no loader read is a misspelling
  return c;
}

}  // namespace ehc_perception
