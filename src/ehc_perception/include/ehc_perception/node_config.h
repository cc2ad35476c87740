#pragma once
// The configurations of the perception nodes (ehc_tag_node, ehc_grasp_node, ehc_obstacle_node):
// typed structs with defaults, each loaded from the node's YAML file (_config:=, see
// config/perception/) through ConfigNode. A bad value throws std::invalid_argument naming the
// file and the field; a key no loader reads (a misspelling) is an error. ROS-free: the nodes pass
// the file path and use the result.

#include "ehc_perception/grasp_generator.h"
#include "ehc_perception/obstacle_distance_field.h"
#include "ehc_perception/obstacle_monitor.h"
#include "ehc_perception/tag_detector.h"

#include <string>
#include <vector>

namespace ehc_perception {

/// ehc_tag_node: camera image + camera_info -> the target pose.
struct TagNodeConfig {
  std::string image_topic = "/camera/color/image_raw";
  std::string camera_info_topic = "/camera/color/camera_info";
  std::string target_topic = "/ehc/target_pose";
  std::string world_frame = "odom";
  std::string camera_frame;  ///< "" = the image's header.frame_id
  std::string camera_file;   ///< optional camera_info YAML; "" = use the camera_info topic
  double tf_timeout = 0.05;  ///< wall s an image waits for its camera pose (lock-step: the node's own wait)
  /// s: an image that waited longer in the node (receipt to processing, the node's clock) is
  /// dropped as stale (timer mode; in lock-step the simulator waits for the node). The
  /// subscription keeps the newest image only.
  double stale_after = 0.5;
  /// Pixels of an image at most (1920x1080, the D435's largest colour mode): a larger one is
  /// dropped before any per-pixel work; so is one of another size than the camera's.
  int max_image_pixels = 1920 * 1080;
  TagDetectorConfig detector;
  TagTargetConfig target;

  /// Throws std::invalid_argument "[TagNodeConfig] parameter 'node.<field>' ..." (tf_timeout in
  /// [0, 5] s, stale_after in [0.01, 10] s, max_image_pixels in [1, 10^8], world_frame not
  /// empty), then the detector's and the target's own validation.
  void validate() const;
  std::string summary() const;
  /// The topics the node needs a publisher on before it takes part in a lock-step
  /// (ehc_common::LockstepAck): the images, /tf and, without camera_file, the camera_info topic.
  std::vector<std::string> lockstepInputs() const;
};

/// Reads `path`: a `node` mapping (optional; the fields above, camera_file relative to the file's
/// folder), `tag_detector` (loadTagDetectorConfig) and `target` (loadTagTargetConfig). Throws
/// std::invalid_argument naming the file and the field on a bad value or an unknown key.
TagNodeConfig loadTagNodeConfig(const std::string& path);

/// ehc_grasp_node: depth cloud -> grasp candidates near the target.
struct GraspNodeConfig {
  std::string cloud_topic = "/camera/depth/points";
  std::string target_topic = "/ehc/target_pose";  ///< "" = no target: every object
  std::string output_topic = "/ehc/grasp_candidates";
  /// The current object's target selector (ehc_msgs/TargetSelector, the sequencer's, latched);
  /// "" = none: every target is a tag's. A cloud selector: generateForCloudTarget, and the
  /// target's pose (ehc_control::cloudTargetPose) on cloud_target_topic.
  std::string selector_topic = "/ehc/sequencer/target_selector";
  std::string cloud_target_topic = "/ehc/perception/cloud_target";
  std::string world_frame = "odom";
  GraspTargetingParams targeting;  ///< max rate, point budget, target timeout and gate
  double tf_timeout = 0.1;  ///< wall s a cloud waits for its camera pose (lock-step: the node's own wait)
  /// s: a cloud that waited longer in the node (receipt to processing, the node's clock) is
  /// dropped as stale (timer mode; in lock-step the simulator waits for the node). The
  /// subscription keeps the newest cloud only.
  double stale_after = 0.5;
  GraspGeneratorConfig generator;

  /// Throws std::invalid_argument "[GraspNodeConfig] parameter 'node.<field>' ..." (tf_timeout in
  /// [0, 5] s, stale_after in [0.01, 10] s), then the targeting's and the generator's own
  /// validation.
  void validate() const;
  std::string summary() const;
  /// The topics the node needs a publisher on before it takes part in a lock-step: the clouds,
  /// the target topic (when set) and /tf.
  std::vector<std::string> lockstepInputs() const;
};

/// Reads `path`: a `node` mapping (optional; the fields above, the targeting fields
/// loadGraspTargetingParams reads) and `grasp_generator` (loadGraspGeneratorConfig). Throws
/// std::invalid_argument naming the file and the field on a bad value or an unknown key.
GraspNodeConfig loadGraspNodeConfig(const std::string& path);

/// ehc_obstacle_node: depth clouds + robot state -> link-obstacle distances.
struct ObstacleNodeConfig {
  std::string robot_config;  ///< robot.yaml (relative paths: to the config file's folder)
  std::string cloud_topic = "/camera/depth/points";
  std::string joint_states_topic = "/joint_states";
  std::string odom_topic = "/odom";
  std::string output_topic = "/ehc/obstacles";
  std::string exclusion_topic = "/ehc/obstacle_exclusion";  ///< "" = no exclusions
  std::string world_frame = "odom";
  double publish_rate_hz = 50.0;
  double tf_timeout = 0.05;       ///< s
  /// s: a cloud that waited longer in the node (receipt to processing, the node's clock) is
  /// dropped as stale (timer mode; in lock-step the simulator waits for the node). The robot's
  /// own points are removed with its pose at processing: a cloud older than the state timeout
  /// would be filtered with the wrong pose.
  double stale_after = 0.2;
  ObstacleMonitorParams monitor;  ///< state / exclusion timeouts, insert rate, point budgets
  ObstacleMapConfig map;

  /// Throws std::invalid_argument "[ObstacleNodeConfig] parameter 'node.<field>' ..."
  /// (publish_rate_hz in [0.1, 1000] Hz, tf_timeout in [0, 5] s, stale_after in [0.01, 10] s),
  /// then the monitor's and the
  /// map's own validation. robot_config is checked by the loader (robotFileField).
  void validate() const;
  std::string summary() const;
  /// The topics the node needs a publisher on before it takes part in a lock-step: the clouds,
  /// the joint states, the odometry, /tf and the exclusion topic (when set).
  std::vector<std::string> lockstepInputs() const;
};

/// Reads `path`: a required `node` mapping (robot_config required: a robot name or a robot.yaml
/// path, ehc_control::robotFileField; the fields above; the monitor's fields,
/// loadObstacleMonitorParams) and `obstacle_map` (loadObstacleMapConfig). Throws
/// std::invalid_argument naming the file and the field on a bad value or an unknown key.
ObstacleNodeConfig loadObstacleNodeConfig(const std::string& path);

}  // namespace ehc_perception
