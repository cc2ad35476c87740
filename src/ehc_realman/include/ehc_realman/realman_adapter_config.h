#pragma once
// Parameters of the rm_arm_adapter node (config/realman/rm_arm_adapter.yaml), loaded and
// validated in one place so that a bad file fails at start-up naming the file and the field.

#include "ehc_realman/realman_joint_streamer.h"

#include <string>

namespace ehc_realman {

struct RmArmAdapterConfig {
  std::string source_file;  ///< the YAML this came from ("" if built in code)
  std::string robot_file;   ///< robot.yaml (joint names, limits, velocity limits)
  ArmJointLimits limits;    ///< from robot_file
  JointStreamerConfig stream;
  GripperConfig gripper;
  double status_rate_hz = 1.0;  ///< adapter diagnostics publication rate

  void validate() const;  ///< throws "[RmArmAdapterConfig] ..."
  std::string summary() const;
};

/// Reads `rm_arm_adapter:` from `path`; `robot:` is resolved against the file's folder and loaded
/// with ehc_control::loadRobotConfig. Throws std::invalid_argument naming file and field.
RmArmAdapterConfig loadRmArmAdapterConfig(const std::string& path);

}  // namespace ehc_realman
