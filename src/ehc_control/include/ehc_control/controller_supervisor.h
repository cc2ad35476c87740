#pragma once
// ControllerSupervisor: the safety logic around the QP (ROS-free, unit-tested):
// validates every input (size, finiteness), remembers the last good robot state, target and
// obstacles with their receipt times, and decides each cycle whether the controller may run or
// must stop (stale joint state, odometry or target; no target yet; with require_obstacles, a
// missing or stale obstacle list). The node only converts messages and publishes what the
// supervisor and the QP decide. Times are seconds of the CONSUMING node's clock (receipt
// times): a sender's clock offset cannot stretch a timeout. An input from the future (a clock
// that jumped back) counts as stale too.

#include "ehc_control/qp_controller.h"

#include <Eigen/Geometry>

#include <optional>
#include <string>
#include <vector>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_control {

struct SupervisorParams {
  double state_timeout = 0.2;      ///< s: joint state / odometry older than this stops the robot
  double target_timeout = 0.2;     ///< s: target older than this stops the robot (TARGET_LOST)
  double obstacle_timeout = 0.5;   ///< s: older obstacle lists are dropped
  /// Obstacle sensing is required (the default: safe unless a config says otherwise): a missing
  /// obstacle list, or one older than obstacle_timeout, stops the robot (OBSTACLES_STALE)
  /// instead of tracking blind. false (no obstacle node, e.g. free-space experiments): the
  /// controller tracks without obstacle dampers when no fresh list is in, and says so (node
  /// start-up warning, ControlCycleStatus::obstacles_required in every status).
  bool require_obstacles = true;
  /// s: a cycle (servo + QP build + solve) that took longer on the cycle's clock
  /// (ControlCycle::setClock; the node: ROS time) gives a zero command, QP_FAILED, "... over
  /// max_solve_time". The solve is bounded (controller.max_qp_iterations, DualActiveSetQp);
  /// with the rows bounded too, an overrun means a starved CPU, and the command would be late. Without a clock (offline runs) not checked.
  double max_solve_time = 0.05;
  void validate() const;           ///< throws "[SupervisorParams] ..."
  std::string summary() const;
};
SupervisorParams loadSupervisorParams(const ehc_common::ConfigNode& node);

struct SupervisorDecision {
  bool run = false;
  ControlPhase phase = ControlPhase::Tracking;  ///< when !run: Stopped | ObstaclesStale | Idle | TargetLost
  std::string reason;  ///< human-readable, empty when run
};

class ControllerSupervisor {
 public:
  ControllerSupervisor(const RobotConfig& robot, const SupervisorParams& params);

  /// Arm joint state by name (extra names such as finger joints are ignored). Returns "" if
  /// accepted, else why it was rejected (state unchanged).
  std::string setJointState(double t, const std::vector<std::string>& names,
                            const std::vector<double>& positions);
  std::string setBasePose(double t, const Eigen::Vector3d& base_pose);
  std::string setTarget(double t, const Eigen::Isometry3d& target);
  std::string setObstacles(double t, const std::vector<ObstaclePair>& obstacles);
  void clearTarget();

  /// In this order: joint state / odometry missing or stale -> Stopped; obstacles required and
  /// missing or stale -> ObstaclesStale; no target -> Idle; stale target -> TargetLost; else run.
  SupervisorDecision check(double now) const;

  const Eigen::VectorXd& q() const { return q_; }
  const Eigen::Vector3d& basePose() const { return base_; }
  const Eigen::Isometry3d& target() const { return target_; }
  bool hasTarget() const { return t_target_.has_value(); }
  /// Seconds since the last good target pose was received (-1 if none). The controller keeps
  /// serving that pose while the age is within target_timeout, then stops (TARGET_LOST);
  /// a fresh pose resumes it.
  double targetAge(double now) const { return t_target_ ? now - *t_target_ : -1.0; }
  /// Seconds since the older of the last good joint state and odometry (-1 if either is missing).
  double stateAge(double now) const;
  /// Seconds since the last good obstacle list (-1 if none).
  double obstaclesAge(double now) const { return t_obstacles_ ? now - *t_obstacles_ : -1.0; }
  /// Obstacles if fresh, else an empty list (valid until the next setObstacles).
  const std::vector<ObstaclePair>& obstacles(double now) const;
  const SupervisorParams& params() const { return params_; }
  double jointStateTime() const { return t_joints_.value_or(-1.0); }
  long rejected() const { return rejected_; }

 private:
  RobotConfig robot_;
  SupervisorParams params_;
  Eigen::VectorXd q_;
  Eigen::Vector3d base_ = Eigen::Vector3d::Zero();
  Eigen::Isometry3d target_ = Eigen::Isometry3d::Identity();
  std::vector<ObstaclePair> obstacles_;
  std::optional<double> t_joints_, t_base_, t_target_, t_obstacles_;
  long rejected_ = 0;
};

/// The watchdogs for the time when NO control cycle runs (ControllerSupervisor judges the inputs
/// of a cycle that does run). The node reports every cycle (cycleRan) and asks on its timers
/// whether to publish a zero command (ControlCycle::stopped) instead:
///   - ROS-time watchdog (lock-step, checkRosTime): no cycle for more than state_timeout of ROS
///     time, either way (a clock that jumped back counts too): the state was lost while /clock
///     runs;
///   - wall-clock watchdog (every mode, checkWallClock, called periodically): no cycle for more
///     than wall_timeout wall seconds while ROS time has stood still as long (a dead simulator
///     stops /clock as well). While ROS time moves, however slowly (a lock-step simulator under
///     load), only the ROS-time rules decide.
/// Neither fires before the first cycle. Times in seconds of the ROS clock and of the wall clock
/// (any origins).
class CycleWatchdog {
 public:
  /// Throws std::invalid_argument "[CycleWatchdog] ..." unless both timeouts are > 0.
  CycleWatchdog(double state_timeout, double wall_timeout);

  /// A control cycle ran at ROS time `ros_now`, wall time `wall_now`.
  void cycleRan(double ros_now, double wall_now);
  /// "" while the last cycle is within state_timeout of `ros_now` (or none ran yet), else why
  /// the robot must stop: "no control cycle for <s> s (lock-step: no joint state + odometry pair)".
  std::string checkRosTime(double ros_now) const;
  /// "" unless no cycle ran for more than wall_timeout wall seconds and ROS time has not moved
  /// for as long (since the first call that saw it at `ros_now`), else why the robot must stop:
  /// "no control cycle for <s> wall s (ROS time <t> stands still? simulator dead?)". Remembers
  /// when ROS time last moved: call it periodically.
  std::string checkWallClock(double wall_now, double ros_now);

 private:
  double state_timeout_, wall_timeout_;
  std::optional<double> last_cycle_ros_, last_cycle_wall_;
  double last_ros_time_ = 0.0;          ///< ROS time seen by the last checkWallClock
  double last_ros_advance_wall_ = 0.0;  ///< wall time at which ROS time last moved
};

}  // namespace ehc_control
