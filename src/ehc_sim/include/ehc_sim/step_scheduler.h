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
//     Wall-clock rules only resend or delay, never step: a state not fully answered (the two
//     commands) is published again (RepublishState, statePublished(.., fresh = false)) every
//     state_republish_period wall seconds, for a controller that starts late, missed the
//     message, or whose answer (or half of it) was lost while its publishers were connecting; with max_real_time_factor > 0 an
//     answered step waits until dt / max_real_time_factor wall seconds have passed since the
//     state was published (pacing for tests whose other inputs come on wall-clock timers).
// Acknowledgement gate (lock-step only, off unless setAckGate names nodes): nodes
// outside the controller's handshake that must be done with what the simulator published before
// sim time moves on. Each listed node consumes one stream: the images, the depth clouds or the
// fresh states (e.g. the grasp sequencer, which turns each controller status into the next
// goal). A frame (image, cloud or state) stamped s must be acknowledged (onAck with that stamp
// or a later one) by every node of its stream before a step takes sim time past s + max_lag.
// A node joins the gate with its first acknowledgement (one that has not started yet, or has
// not subscribed yet, holds nothing back: it could never acknowledge the frames before it);
// ehc_sim_node waits for every node's "ready" acknowledgement (notJoined, ehc_common::LockstepAck)
// before its first state, so in practice every node is there from the start.
// Without the gate a loaded machine let these nodes fall behind sim time (fewer images
// processed per sim second: the back object's tag, detectable only from close, was never seen
// in one run; the grasp candidates and the next goal arrived one or more cycles later), so
// results depended on the load.
// Free-run (free_run = true): a step every dt of wall time (no catching up after a stall)
// with the latest commands; arm commands need no matching stamp; both groups are zeroed when
// either the last /cmd_vel or the last accepted arm command is older than command_timeout.

#include "ehc_sim/command_gate.h"
#include "ehc_sim/fake_robot_config.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace ehc_sim {

/// What a node of the acknowledgement gate consumes.
enum class AckStream {
  State,  ///< every fresh state (statePublished(.., fresh = true))
  Image,  ///< every camera image (framePublished)
  Cloud,  ///< every depth cloud (framePublished)
};
const char* toString(AckStream s);

/// A node of the acknowledgement gate and its stream.
struct AckNode {
  std::string name;
  AckStream stream = AckStream::Image;
  /// "name" (an image consumer) or "name:stream" with stream state | image | cloud; throws
  /// std::invalid_argument ("[StepScheduler] ...") on an empty name or an unknown stream.
  static AckNode parse(const std::string& spec);
};

/// The acknowledgement gate as the simulator node's parameters give it (_lockstep_acks,
/// _lockstep_max_lag), parsed and checked here so that the node only reads parameters.
struct AckGateConfig {
  std::vector<AckNode> nodes;  ///< empty: no gate
  double max_lag = 0.0;        ///< s, [0, 10]: how far sim time may pass a frame not yet acknowledged
  std::int64_t maxLagNs() const;
  /// " name (stream)" for every node, e.g. " ehc_tag_node (image) ehc_grasp_node (cloud)".
  std::string summary() const;
};
/// AckNode::parse of every spec and the lag. Throws std::invalid_argument "[StepScheduler] ..."
/// naming the bad spec (an empty name, an unknown stream) or a lag outside [0, 10] s.
AckGateConfig parseAckGate(const std::vector<std::string>& specs, double max_lag_s);

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

  /// Acknowledgement gate (see the file comment): `nodes` (empty: off) must acknowledge every
  /// frame of their stream before sim time passes its stamp by more than `max_lag_ns` (>= 0).
  /// Lock-step only. Throws std::invalid_argument on a negative lag, an empty or repeated name.
  void setAckGate(const std::vector<AckNode>& nodes, std::int64_t max_lag_ns);
  /// An image or a cloud stamped `stamp_ns` was published (states are recorded by statePublished).
  void framePublished(AckStream stream, std::int64_t stamp_ns);
  /// `node` is done with the frames of its stream up to `stamp_ns` (whatever came of them): ""
  /// if counted, else why not: a node the gate does not list, or a stamp more than one step
  /// ahead of the newest frame published (no such frame exists: a wrong clock or a stray
  /// publisher; counting it would let sim time run past frames nobody processed).
  std::string onAck(const std::string& node, std::int64_t stamp_ns);
  /// "" when no step is held back by the gate; else which node and frame it waits for.
  std::string ackWait() const;
  /// The gate's nodes that have not acknowledged anything yet (a "ready" stamp 0 counts),
  /// space-separated; "" when all have (or the gate is off). The simulator node publishes its
  /// first state only when this is empty, so no node of the gate misses the start.
  std::string notJoined() const;

  bool lockStep() const { return !config_.free_run; }
  const CommandGate& gate() const { return gate_; }
  const CommandCounters& counters() const { return gate_.counters(); }

 private:
  FakeRobotConfig config_;
  CommandGate gate_;
  double last_publish_ = 0.0;
  double last_fresh_publish_ = 0.0;
  std::optional<double> last_base_cmd_, last_arm_cmd_, next_step_;
  std::int64_t state_ns_ = 0;  ///< stamp of the last fresh state
  std::int64_t newest_ns_ = 0;  ///< stamp of the newest frame (state, image, cloud) published
  long future_acks_ = 0;        ///< acknowledgements ignored for a stamp ahead of newest_ns_
  // Acknowledgement gate: listed nodes, their last acknowledged stamp (-1: not joined), the
  // frames per stream (increasing) not yet acknowledged by every joined node of the stream.
  std::vector<AckNode> ack_nodes_;
  std::vector<std::int64_t> acked_ns_;
  std::int64_t max_lag_ns_ = 0;
  std::array<std::vector<std::int64_t>, 3> frames_ns_;
  void recordFrame(AckStream stream, std::int64_t stamp_ns);
  /// Index of a node that has not acknowledged the newest frame of its stream the next step
  /// must not pass (-1: none), and that frame's stamp.
  int heldBy(std::int64_t* frame_ns) const;
};

}  // namespace ehc_sim
