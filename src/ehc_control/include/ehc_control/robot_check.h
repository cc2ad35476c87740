#pragma once
// RobotCheck: what will go wrong with a robot folder, before anything runs (`ehc_kinematics
// --check`). Every check reports on its own, one line per problem, so that a new user sees all
// that is wrong at once:
//  - robot.yaml loads (required fields present: URDF, base type and limits, arm joints with
//    lower, upper and velocity limits) and its URDF parses;
//  - every link robot.yaml names in robot.frames (base = the URDF root, arm_base, tcp,
//    camera_optical) is in the URDF, and so are the calibration joints (fixed joints);
//  - the arm joints are movable joints of the URDF forming the chain arm_base -> tcp in order;
//  - joint limits: ranges of at most two turns either way, velocities within
//    [min_joint_velocity, max_joint_velocity], inside the URDF's limits, and the ready pose at
//    least the controller's joint stop (QpControllerParams::joint_stop) from every limit;
//  - the hand: the camera and the gripper hang below the last arm joint, and the gripper has
//    exactly two prismatic finger joints of the same travel (the simulator's gripper);
//  - the camera: camera_info loads and, in the ready pose with the base at the scene's start
//    (origin, facing +x), every corner of the view region ahead projects into the image;
//  - the reachability map: loads, names this robot, frames and joint count, and the arm's
//    kinematics (joint limits, TCP at the map's reference configurations) match it.
// ROS-free.

#include <Eigen/Core>

#include <string>
#include <vector>

namespace ehc_control {

struct RobotCheckParams {
  /// The region ahead that the ready pose's camera must see (base frame at the scene's start:
  /// x forward, z up; m): by default the box around the three tags of the Exp-2 table
  /// (config/scenes/table_three_objects.yaml: 1.6 to 1.9 m ahead, up to 0.17 m either side,
  /// 0.78 to 0.84 m high; a test of the scene keeps the two together).
  Eigen::Vector3d view_min{1.59, -0.175, 0.775};
  Eigen::Vector3d view_max{1.91, 0.175, 0.845};
  double view_max_distance = 3.0;  ///< m: farther corners count as unseen (depth range, tag size)
  double image_margin_px = 5.0;    ///< a corner must lie this far inside the image border
  double min_joint_velocity = 0.05;  ///< rad/s (or m/s): slower arm joints are absurd
  double max_joint_velocity = 10.0;  ///< rad/s (or m/s): faster arm joints are absurd
  double max_joint_range = 4.0 * 3.14159265358979323846 + 1e-9;  ///< rad: upper - lower
  /// rad: the ready pose's least distance to a joint limit; default the controller's joint_stop.
  double ready_margin;
  RobotCheckParams();
  void validate() const;  ///< throws "[RobotCheck] ..."
};

struct RobotCheckLine {
  std::string check;    ///< e.g. "frames", "fingers", "camera view", "reachability map"
  bool ok = true;
  std::string message;  ///< what was found (ok) or what is wrong and how to fix it
};

/// Runs every check on the robot.yaml at `robot_file`. Never throws for a problem of the robot
/// folder (each becomes a line with ok == false); checks that need what failed earlier are
/// left out. Throws "[RobotCheck] ..." only for invalid params.
std::vector<RobotCheckLine> checkRobot(const std::string& robot_file, const RobotCheckParams& params = {});

/// True when every line is ok.
bool allOk(const std::vector<RobotCheckLine>& lines);
/// "ok <check>: <message>" or "PROBLEM <check>: <message>".
std::string toString(const RobotCheckLine& line);

}  // namespace ehc_control
