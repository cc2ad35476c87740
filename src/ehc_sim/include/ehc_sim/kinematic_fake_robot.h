#pragma once
// KinematicFakeRobot: integrates base + arm velocity commands with Gaussian actuation noise
// (paper Table I), saturates at the velocity limits and clamps at the joint limits. The
// differential base moves as a unicycle. The base model (base_model.h) decides how the base
// executes its command and what the odometry reports: `ideal` (at once; odometry = true pose)
// or `water2` (latency, 0.5 s hold, acceleration limits, lag, gain error, ~2 Hz odometry with
// error); the base imprecision (BaseImprecisionParams, level > 0) acts on top of either. ROS-free; the Bullet simulator builds on it.

#include "ehc_control/robot_config.h"
#include "ehc_sim/base_model.h"

#include <Eigen/Core>

#include <optional>
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
  /// Throws "[KinematicFakeRobot] ..." for the water2 base model on a holonomic base.
  KinematicFakeRobot(const ehc_control::RobotConfig& robot, const ActuationNoise& noise,
                     unsigned seed, const BaseModelConfig& base_model = BaseModelConfig());

  /// Puts the robot at a base pose (x, y, yaw) and arm configuration; reseeds the noise.
  void reset(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q, unsigned seed);

  /// Executes `command` = [base twist (base frame); arm joint rates] for `dt` seconds.
  /// Commands beyond the velocity limits are saturated (counted). A base command inside the
  /// deadband and an exactly zero arm command are executed as standing still (no noise). Throws
  /// "[KinematicFakeRobot] ..." on a wrong size, NaN/Inf or dt <= 0. Water2: the base command is
  /// this step's /cmd_vel into the Water2 chain (the bridge scales it keeping the turn radius).
  void step(const Eigen::VectorXd& command, double dt);

  /// Water2 only (throws otherwise): a joy_control the base receives over its API now (the
  /// hardware stand-in's Water2ApiServer). From then on step()'s base command must be zero: the
  /// base executes only what arrives here (Water2BaseModel::joyControlReceived).
  void joyControlReceived(double linear, double angular);
  /// Water2 only: what the base's robot_status reports now (map pose = true pose + error).
  Eigen::Vector3d statusPose() const;

  /// The true base pose (x, y, yaw) in the world (= odom at time 0).
  const Eigen::Vector3d& basePose() const { return base_; }
  /// What /odom reports (the controller's base pose): ideal = basePose(), or with the base
  /// imprecision the odometry (wheel twist, localisation fixes); water2 = the bridge's estimate
  /// from the ~2 Hz status (which reports the imprecise odometry when the imprecision is on).
  Eigen::Vector3d odometryPose() const;
  /// The /odom twist (v_x, v_y, w_z), base frame: ideal = the executed base velocity (with the
  /// imprecision: the wheel twist, without slip and systematic errors); water2 = the base
  /// velocity the bridge predicts from the twists it sent.
  Eigen::Vector3d odometryTwist() const;
  /// True when /odom is the true pose (the ideal base without imprecision).
  bool odometryIsTruth() const { return !water2_ && !imprecision_; }
  const BaseModelConfig& baseModel() const { return base_model_; }
  /// The Water2 chain (nullptr for the ideal base).
  const Water2BaseModel* water2() const { return water2_ ? &*water2_ : nullptr; }
  /// The base imprecision (nullptr at level 0).
  const BaseImprecision* imprecision() const { return imprecision_ ? &*imprecision_ : nullptr; }
  const Eigen::VectorXd& armPositions() const { return q_; }
  /// Velocity actually executed in the last step (after saturation, noise, joint limits; the
  /// base's true twist).
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
  BaseModelConfig base_model_;
  std::optional<Water2BaseModel> water2_;
  std::optional<BaseImprecision> imprecision_;
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
