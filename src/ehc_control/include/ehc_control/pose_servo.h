#pragma once
// ProportionalPoseServo: position-based servo law nu_e = K [t* - t; k_r theta u] in the world
// frame (the p_servo of the NEO reference). Output saturated per component group so that a far
// target does not ask for an absurd twist. ROS-free.

#include <Eigen/Geometry>

namespace ehc_control {

class ConfigNode;

struct PoseServoParams {
  double gain = 1.5;                ///< 1/s, translation gain
  double rotation_gain_ratio = 1.3; ///< rotation gain = gain * ratio (NEO: 1.3)
  double max_linear = 2.0;          ///< m/s, |v| saturation of the desired twist
  double max_angular = 2.0;         ///< rad/s, |w| saturation of the desired twist
  void validate() const;            ///< throws "[PoseServoParams] ..."
};
PoseServoParams loadPoseServoParams(const ConfigNode& node);

/// Desired TCP twist [v; w] (world frame) towards `target`.
Eigen::Matrix<double, 6, 1> proportionalPoseServo(const Eigen::Isometry3d& tcp,
                                                  const Eigen::Isometry3d& target,
                                                  const PoseServoParams& params);

}  // namespace ehc_control
