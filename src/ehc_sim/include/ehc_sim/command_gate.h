#pragma once
// CommandGate: validates the velocity commands the simulator receives and decides when a
// lock-step simulation may advance. Contract (DESIGN.md section 4): after the simulator
// publishes the state stamped t, the controller answers with /cmd_vel and then a
// JointVelocityCommand stamped t; the simulator steps once it holds the arm command stamped t
// AND at least one base twist received since the last step. Non-finite, wrongly sized or
// over-limit commands are rejected (counted) and replaced by zero velocities for their group,
// so the robot stops safely and lock-step keeps going. ROS-free.

#include "ehc_control/robot_config.h"

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace ehc_sim {

struct CommandCounters {
  long base_accepted = 0, base_rejected = 0;
  long arm_accepted = 0, arm_rejected = 0;
  long arm_stale = 0;  ///< arm commands whose stamp is not the current state's (ignored)
};

class CommandGate {
 public:
  explicit CommandGate(const ehc_control::RobotConfig& robot);

  /// Starts a new state at `stamp_ns` (after a step or a reset): forgets the commands.
  void newState(std::int64_t stamp_ns);

  /// /cmd_vel. Returns "" if accepted, else the reason (the base is then commanded zero).
  /// vy must be 0 for a differential base.
  std::string onBaseTwist(double vx, double vy, double wz);
  /// /arm/joint_velocity_cmd stamped `stamp_ns`. `names` may be empty (= command order) or a
  /// permutation of the arm joints. A command for another stamp is stale (counted, ignored in
  /// lock-step, used in free-run). Returns "" if accepted, else the reason (the arm is then
  /// commanded zero for this state).
  std::string onArmCommand(std::int64_t stamp_ns, const std::vector<std::string>& names,
                           const std::vector<double>& velocities, bool require_stamp = true);

  /// Lock-step: both answers for the current state are in.
  bool ready() const { return arm_answered_ && base_since_step_; }
  /// The command vector [base twist; arm rates] to execute (zeros for rejected parts).
  Eigen::VectorXd command() const;
  /// Zeroes the held commands (free-run command timeout).
  void zero();

  std::int64_t stamp() const { return stamp_ns_; }
  const CommandCounters& counters() const { return counters_; }
  void resetCounters() { counters_ = CommandCounters(); }

 private:
  ehc_control::RobotConfig robot_;
  Eigen::VectorXd vmax_;
  Eigen::VectorXd base_;
  Eigen::VectorXd arm_;
  std::int64_t stamp_ns_ = 0;
  bool arm_answered_ = false;
  bool base_since_step_ = false;
  CommandCounters counters_;
};

}  // namespace ehc_sim
