#pragma once
// StepScheduler: the one stepping policy of both fake robots (ehc_sim_node with Bullet,
// ehc_kinematic_sim_node without), around their CommandGate. The node reports every event with
// the wall-clock time it happened at (seconds, any monotonic origin), asks next() what to do,
// and executes command() when told to step. ROS-free.
//
// Lock-step (FakeRobotConfig::free_run = false, the default):
//   - the node publishes the state stamped t (statePublished(.., fresh = true));
//   - it steps only once the gate is ready: the JointVelocityCommand stamped t AND a /cmd_vel
//     since the last step. A rejected command (NaN, wrong size, over a limit) is an answer: it
//     is counted and its group executed as zero, so lock-step never stalls on a bad command;
//   - sim time never advances on a timeout: a controller that stops answering stops time.
//     Wall-clock rules only resend or delay, never step: a state NOBODY answered (no command of
//     either kind since it was published) is published again (RepublishState,
//     statePublished(.., fresh = false)) every state_republish_period wall seconds, for a
//     controller that starts late or missed the message; with max_real_time_factor > 0 an
//     answered step waits until dt / max_real_time_factor wall seconds have passed since the
//     state was published (pacing for tests whose other inputs come on wall-clock timers).
// Free-run (free_run = true): a step every dt of wall time (no catching up after a stall)
// with the latest commands; arm commands need no matching stamp; both groups are zeroed when
// either the last /cmd_vel or the last accepted arm command is older than command_timeout.

#include "ehc_sim/command_gate.h"
#include "ehc_sim/fake_robot_config.h"

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace ehc_sim {

enum class StepAction {
  Wait,            ///< nothing to do yet: keep serving callbacks
  Step,            ///< step once with command(), then publish the new state (fresh)
  RepublishState,  ///< publish the current state again (not fresh)
};
const char* toString(StepAction a);

class StepScheduler {
 public:
  /// Uses config.free_run, dt, state_republish_period and command_timeout.
  StepScheduler(const ehc_control::RobotConfig& robot, const FakeRobotConfig& config);

  /// The node published the state stamped `stamp_ns` at wall time `wall_s`. `fresh`: a new
  /// sim time (start, after a step or a reset): the previous state's commands no longer count.
  void statePublished(double wall_s, std::int64_t stamp_ns, bool fresh);
  /// /cmd_vel received at `wall_s`: CommandGate::onBaseTwist ("" = accepted, else the reason).
  std::string onBaseTwist(double wall_s, double vx, double vy, double wz);
  /// /arm/joint_velocity_cmd stamped `stamp_ns` received at `wall_s`: CommandGate::onArmCommand
  /// (the stamp must match the state in lock-step only).
  std::string onArmCommand(double wall_s, std::int64_t stamp_ns, const std::vector<std::string>& names,
                           const std::vector<double>& velocities);
  /// What to do at wall time `wall_s`. In free-run a Step may zero stale commands first.
  StepAction next(double wall_s);
  /// How long (wall s) the node may block waiting for callbacks before asking next() again.
  double callbackWait() const;

  /// [base twist; arm rates] to execute on a Step (zeros for rejected or zeroed groups).
  Eigen::VectorXd command() const { return gate_.command(); }
  /// After a scene reset: zero commands and counters (then publish a fresh state).
  void reset();

  bool lockStep() const { return !config_.free_run; }
  const CommandGate& gate() const { return gate_; }
  const CommandCounters& counters() const { return gate_.counters(); }

 private:
  FakeRobotConfig config_;
  CommandGate gate_;
  bool answered_ = false;  ///< any command since the last fresh state
  double last_publish_ = 0.0;
  double last_fresh_publish_ = 0.0;
  std::optional<double> last_base_cmd_, last_arm_cmd_, next_step_;
};

}  // namespace ehc_sim
