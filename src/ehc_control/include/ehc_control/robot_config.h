#pragma once
// RobotConfig: everything about the robot that is not in the URDF (base type and limits,
// arm joint order and limits, frame names, hand-eye calibration, camera intrinsics, the links
// the obstacle field / simulator check, per-link obstacle stop distances), loaded from
// robot.yaml. Every robot-specific name lives here (config/robots/<name>/robot.yaml); generic
// configs (control, sim, perception, demo) name no link. The link names are checked against
// the URDF by WholeBodyModel (a name the robot does not have is an error naming the file and
// field).

#include <Eigen/Core>

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_control {

enum class BaseType {
  Holonomic,     ///< base twist columns v_x, v_y, w_z (base frame)
  Differential,  ///< base twist columns v_x, w_z (unicycle)
};

std::string toString(BaseType t);
BaseType baseTypeFromString(const std::string& s);  ///< throws std::invalid_argument

/// A fixed URDF joint whose origin is replaced by a calibrated value (TCP, camera mount).
struct FrameOverride {
  std::string key;    ///< "tcp" | "camera": the field robot.calibration.<key>
  std::string joint;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  Eigen::Vector3d rpy = Eigen::Vector3d::Zero();
};

struct RobotConfig {
  std::string name = "robot";
  std::string source_file;  ///< the robot.yaml this came from ("" if built in code)
  std::string urdf_path;    ///< absolute or relative to the working directory
  std::string reachability_map_path;  ///< optional; "" = none (ehc mode then needs one)

  std::string world_frame = "odom";
  std::string base_frame = "base_link";
  std::string arm_base_frame = "arm_base_link";
  std::string tcp_frame = "ee_link";
  std::string camera_frame = "camera_color_optical_frame";

  BaseType base_type = BaseType::Differential;
  double max_linear_velocity = 0.5;   ///< m/s, |v| bound of the base
  double max_angular_velocity = 1.0;  ///< rad/s, |w| bound of the base

  std::vector<std::string> arm_joints;  ///< command order
  Eigen::VectorXd arm_lower;            ///< rad
  Eigen::VectorXd arm_upper;            ///< rad
  Eigen::VectorXd arm_velocity;         ///< rad/s, symmetric bound
  Eigen::VectorXd arm_ready;            ///< rad, initial / ready pose

  std::vector<FrameOverride> calibration;

  /// camera_info YAML of the hand camera (intrinsics: simulated camera, TfM in-view test);
  /// "" = none (the controller then uses PinholeCamera's defaults).
  std::string camera_info_path;
  /// robot.collision.checked_links: the links the obstacle field checks against the map, in
  /// this order. Empty = every link with collision geometry (RobotCollisionModel's order).
  std::vector<std::string> checked_links;
  /// robot.collision.floor_links: links that may touch the floor (simulator). Empty = the
  /// URDF's root link.
  std::vector<std::string> floor_links;
  /// robot.collision.ignore_pairs: self-collision pairs never checked, in addition to the
  /// computed ones (adjacent links and pairs in contact in every sampled configuration:
  /// selfCollisionIgnorePairs in self_collision.h).
  std::vector<std::pair<std::string, std::string>> ignore_pairs;
  /// robot.obstacle_stop_distances: per-link obstacle stop distance d_s (m); the other links
  /// use the controller's obstacle_stop.
  std::map<std::string, double> obstacle_stop_distances;

  int nArm() const { return static_cast<int>(arm_joints.size()); }
  int nBase() const { return base_type == BaseType::Holonomic ? 3 : 2; }
  /// Velocity bound of every DOF in [base..., arm...] order.
  Eigen::VectorXd velocityLimits() const;

  /// Range and cross-field checks; throws std::invalid_argument "[RobotConfig] ...".
  void validate() const;
  /// Multi-line human-readable summary (printed once at start-up by nodes and tools).
  std::string summary() const;
};

/// Loads and validates robot.yaml. Relative paths inside are resolved against its folder.
RobotConfig loadRobotConfig(const std::string& path);

/// The stack's config folder (the checkout's config/, absolute; tools work from any working
/// directory); the environment variable EHC_CONFIG_DIR overrides it.
std::string configDirectory();
/// The user's robots folder: the environment variable EHC_ROBOTS_DIR, else the stack's
/// (<configDirectory()>/robots).
std::string robotsDirectory();
/// Where a robot name is looked up, in order: robotsDirectory(), then the stack's robots (so a
/// folder with only the user's robot still finds the shipped robots the configs name).
std::vector<std::string> robotSearchPath();
/// The robots in `dir` (default robotsDirectory()): the names of its folders that hold a
/// robot.yaml, sorted. Tests run over every shipped robot with it.
std::vector<std::string> robotNames(const std::string& dir = robotsDirectory());
/// The one robot switch (--robot, _robot:=, ROBOT=): a robot name (no '/', not ending in
/// .yaml, e.g. "kuka_iiwa14_kmr") -> <dir>/<name>/robot.yaml, the first of robotSearchPath()
/// that has it; anything else is a path to a robot.yaml, returned unchanged. Throws
/// std::invalid_argument "[RobotConfig] ..." for an unknown robot name (listing the known ones).
std::string resolveRobotFile(const std::string& name_or_path);
/// The robot field `key` of a config file (e.g. controller.yaml's `robot`): a robot name as
/// resolveRobotFile, or a path relative to that file's folder. Errors name file and field.
std::string robotFileField(const ehc_common::ConfigNode& node, const std::string& key);

}  // namespace ehc_control
