#pragma once
// RobotConfig: everything about the robot that is not in the URDF (base type and limits,
// arm joint order and limits, frame names, hand-eye calibration), loaded from robot.yaml.

#include <Eigen/Core>

#include <string>
#include <vector>

namespace ehc_control {

enum class BaseType {
  Holonomic,     ///< base twist columns v_x, v_y, w_z (base frame)
  Differential,  ///< base twist columns v_x, w_z (unicycle)
};

std::string toString(BaseType t);
BaseType baseTypeFromString(const std::string& s);  ///< throws std::invalid_argument

/// A fixed URDF joint whose origin is replaced by a calibrated value (TCP, camera mount).
struct FrameOverride {
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

}  // namespace ehc_control
