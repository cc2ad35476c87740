#pragma once
// Joint-state parsing: the one place that turns a joint-state message's (names, positions) into
// the robot's arm configuration, in the order of the arm's joint names (RobotConfig::arm_joints).
// Used by the consumers of /joint_states (ControllerSupervisor, ehc_perception's
// ObstacleMonitor). ROS-free.

#include <Eigen/Core>

#include <string>
#include <vector>

namespace ehc_control {

/// Picks the joints `arm_joints` (e.g. RobotConfig::arm_joints) out of `names` / `positions`
/// (extra names such as finger joints are ignored; the order is free). Returns "" and sets `*q`
/// (in arm_joints order) if every arm joint is present with a finite position; otherwise
/// returns the reason and leaves `*q` unchanged: "joint state has N names but M positions",
/// "joint state lacks arm joint 'x'", "joint state contains NaN or Inf".
std::string armPositionsFromJointState(const std::vector<std::string>& arm_joints,
                                       const std::vector<std::string>& names,
                                       const std::vector<double>& positions, Eigen::VectorXd* q);

}  // namespace ehc_control
