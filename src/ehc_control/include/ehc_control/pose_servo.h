#pragma once
// ProportionalPoseServo: position-based servo law nu_e = K [t* - t; k_r theta u] in the world
// frame (the p_servo of the NEO reference). Output saturated per component group so that a far
// target does not ask for an absurd twist. ROS-free.

#include <Eigen/Geometry>

#include <cmath>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_control {

class WholeBodyModel;

struct PoseServoParams {
  bool unwind_roll = true;          ///< choose the roll direction that keeps the roll joint in range
  double gain = 1.5;                ///< 1/s, translation gain
  double rotation_gain_ratio = 1.3; ///< rotation gain = gain * ratio (NEO: 1.3)
  double max_linear = 2.0;          ///< m/s, |v| saturation of the desired twist
  double max_angular = 2.0;         ///< rad/s, |w| saturation of the desired twist
  void validate() const;            ///< throws "[PoseServoParams] ..."
};
PoseServoParams loadPoseServoParams(const ehc_common::ConfigNode& node);

/// The arm joint that rolls the TCP about its approach (z) axis, e.g. joint6 of the RM65-B.
/// A finite-range roll joint winds up when targets come with random rolls; the servo then
/// rolls the other way round when the short way would take the joint past its limit.
struct RollJoint {
  double q = 0.0;                 ///< current position, rad
  double lower = -M_PI, upper = M_PI;
  double margin = 0.3;            ///< rad kept free at each end
};

/// Index of the arm joint whose axis is the TCP z axis (within 1e-6 at the ready pose), -1 if
/// none.
int findRollJoint(const WholeBodyModel& model);

/// Desired TCP twist [v; w] (world frame) towards `target`. With `roll`, the rotation about
/// the TCP z axis takes the direction that keeps the roll joint inside its range.
Eigen::Matrix<double, 6, 1> proportionalPoseServo(const Eigen::Isometry3d& tcp,
                                                  const Eigen::Isometry3d& target,
                                                  const PoseServoParams& params,
                                                  const RollJoint* roll = nullptr);

/// Roll unwinding for servo laws that cannot be told to rotate more than pi (ViSP's theta-u
/// feature, PbvsServo): when the short way about the TCP z axis would take the roll joint past
/// its range, returns a waypoint rotated halfway along the long way (same translation, same
/// swing), so that the short way to the waypoint is the long way to `target`. Re-evaluated
/// every cycle it leads the joint round; otherwise returns `target` unchanged.
Eigen::Isometry3d rollUnwoundTarget(const Eigen::Isometry3d& tcp, const Eigen::Isometry3d& target,
                                    const RollJoint& roll);

}  // namespace ehc_control
