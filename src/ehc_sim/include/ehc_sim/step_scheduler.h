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
// Perception gate (lock-step only, off unless setPerceptionGate names nodes; issue 18): an
// image published with the state stamped s must be acknowledged (onPerceptionAck, that image or
// a later one) by every listed perception node before a step takes sim time past s + max_lag.
// A node joins the gate with its first acknowledgement (one that has not started yet, or has
// not subscribed yet, holds nothing back: it could never acknowledge the images before it).
// Perception nodes are outside the controller's handshake; without the gate a loaded machine
// let them fall behind sim time (fewer images processed per sim second: the back object's tag,
// detectable only from close, was never seen in one run), so results depended on the load.
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
  /// After a scene reset: zero commands and counters, forget images and acknowledgements (then
  /// publish a fresh state).
  void reset();

  /// Perception gate (see the file comment): `nodes` (empty: off) must acknowledge every image
  /// before sim time passes its stamp by more than `max_lag_ns` (>= 0). Lock-step only.
  void setPerceptionGate(const std::vector<std::string>& nodes, std::int64_t max_lag_ns);
  /// An image stamped `stamp_ns` was published (with the state of that stamp).
  void imagePublished(std::int64_t stamp_ns);
  /// `node` is done with the image stamped `stamp_ns` (whatever came of it): "" if counted,
  /// else why not (a node the gate does not list).
  std::string onPerceptionAck(const std::string& node, std::int64_t stamp_ns);
  /// "" when no step is held back by perception; else which node and image it waits for.
  std::string perceptionWait() const;

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
  std::int64_t state_ns_ = 0;  ///< stamp of the last fresh state
  // Perception gate: listed nodes, their last acknowledged image stamp, images not yet acknowledged by all.
  std::vector<std::string> perception_nodes_;
  std::vector<std::int64_t> acked_ns_;
  std::int64_t max_lag_ns_ = 0;
  std::vector<std::int64_t> images_ns_;  ///< increasing
  /// Index of a node that has not acknowledged the newest image the next step must not pass
  /// (-1: none), and that image's stamp.
  int heldBy(std::int64_t* image_ns) const;
};

}  // namespace ehc_sim
