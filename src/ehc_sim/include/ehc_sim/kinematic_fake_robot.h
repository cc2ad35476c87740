#pragma once
// KinematicFakeRobot: integrates base + arm velocity commands with Gaussian actuation noise
// (paper Table I), saturates at the velocity limits and clamps at the joint limits. The
// differential base moves as a unicycle. ROS-free; the Bullet simulator builds on it.

#include "ehc_control/robot_config.h"

#include <Eigen/Core>

#include <random>

namespace ehc_sim {

/// Actuation model: zero-mean Gaussian noise added to the executed velocity each step
/// (m/s, rad/s), per joint group and only while that group moves. The base has a deadband
/// (static friction of a wheeled base): a base command below it is not executed at all, so a
/// base that is asked to (almost) stand still does not wander. The arm stands still only on an
/// exactly zero command.
struct ActuationNoise {
  bool enabled = true;
  double base_translation = 0.05;  ///< sigma of v_x (and v_y), m/s   (Table I Base-T)
  double base_rotation = 0.05;     ///< sigma of w_z, rad/s          (Table I Base-R)
  double arm = 0.002;              ///< sigma of every arm joint rate, rad/s (Table I Arm)
  double base_deadband_linear = 0.005;   ///< m/s: |v| below (and |w| below its band) = no motion
  double base_deadband_angular = 0.01;   ///< rad/s
  void validate() const;           ///< throws "[ActuationNoise] ..."
};

class KinematicFakeRobot {
 public:
  KinematicFakeRobot(const ehc_control::RobotConfig& robot, const ActuationNoise& noise,
                     unsigned seed);

  /// Puts the robot at a base pose (x, y, yaw) and arm configuration; reseeds the noise.
  void reset(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q, unsigned seed);

  /// Executes `command` = [base twist (base frame); arm joint rates] for `dt` seconds.
  /// Commands beyond the velocity limits are saturated (counted). A base command inside the
  /// deadband and an exactly zero arm command are executed as standing still (no noise). Throws
  /// "[KinematicFakeRobot] ..." on a wrong size, NaN/Inf or dt <= 0.
  void step(const Eigen::VectorXd& command, double dt);

  const Eigen::Vector3d& basePose() const { return base_; }
  const Eigen::VectorXd& armPositions() const { return q_; }
  /// Velocity actually executed in the last step (after saturation, noise, joint limits).
  const Eigen::VectorXd& executedVelocity() const { return executed_; }
  double time() const { return time_; }
  int nDof() const { return robot_.nBase() + robot_.nArm(); }
  long saturatedCommands() const { return saturated_; }
  long jointLimitClamps() const { return clamps_; }
  const ehc_control::RobotConfig& robot() const { return robot_; }
  const ActuationNoise& noise() const { return noise_; }

 private:
  ehc_control::RobotConfig robot_;
  ActuationNoise noise_;
  Eigen::VectorXd vmax_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> gauss_{0.0, 1.0};
  Eigen::Vector3d base_ = Eigen::Vector3d::Zero();
  Eigen::VectorXd q_;
  Eigen::VectorXd executed_;
  double time_ = 0.0;
  long saturated_ = 0;
  long clamps_ = 0;
};

}  // namespace ehc_sim
