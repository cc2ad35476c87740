#pragma once
// JointPositionStreamer: turns joint velocity commands into the stable joint-position stream the
// RealMan rm_driver expects on /rm_driver/JointPos (the driver has no velocity interface).
//
// Every frame: q_next = q_last + v * dt (dt = 1 / rate_hz), where
//   - v is the latest command, scaled down uniformly (direction kept) so that no joint exceeds
//     speed_scale * min(robot velocity limit, driver speed limit);
//   - the set-point integrates from its own last value, never from the measured state; the
//     latest measured /joint_states position only shortens a commanded step that would take the
//     set-point further than max_tracking_error from it (no wind-up when the arm lags or is
//     blocked). That clamp never moves the set-point against the command, so a glitch in the
//     measured state holds the set-point instead of turning into motion;
//   - joint limits (robot.yaml, shrunk by limit_margin) are never crossed outwards;
//   - the step from the previous frame never exceeds min(max_step_deg, v_max * dt) per joint
//     (the driver ignores frames more than 10 deg apart).
// Streaming starts from the measured position when a fresh command arrives while the measured
// state is fresh. When commands (or the measured state) time out the streamer holds the last
// frame for hold_duration, then stops streaming. A latched emergency stop ends streaming at once.
// ROS-free: time is passed in as seconds of a monotonic clock.

#include <Eigen/Core>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace ehc_realman {

struct JointStreamerConfig {
  double rate_hz = 100.0;               ///< JointPos frames per second (driver: 10 ms typical)
  double max_step_deg = 10.0;           ///< driver's hard bound between consecutive frames
  double driver_max_speed_deg = 180.0;  ///< driver's per-joint speed bound (deg/s)
  double speed_scale = 1.0;             ///< (0, 1]: fraction of the velocity limits used
  double command_timeout = 0.2;         ///< s without a command => hold
  double hold_duration = 0.5;           ///< s of holding the last frame before streaming stops
  double state_timeout = 0.2;           ///< s: /joint_states older than this is stale
  double max_tracking_error = 0.2;      ///< rad: |commanded - measured| bound per joint
  double limit_margin = 0.0;            ///< rad kept inside the robot.yaml joint limits
  /// Throws std::invalid_argument "[JointStreamerConfig] ...".
  void validate() const;
};

/// Joint names and limits of the arm, in command order (from robot.yaml).
struct ArmJointLimits {
  std::vector<std::string> names;
  Eigen::VectorXd lower;     ///< rad
  Eigen::VectorXd upper;     ///< rad
  Eigen::VectorXd velocity;  ///< rad/s
  void validate() const;     ///< throws "[ArmJointLimits] ..."
};

enum class StreamPhase { Idle, Streaming, Holding, EmergencyStopped };
std::string toString(StreamPhase p);

/// One frame for /rm_driver/JointPos and what was clamped to produce it.
struct JointFrame {
  Eigen::VectorXd position;  ///< rad, command order
  StreamPhase phase = StreamPhase::Streaming;
  bool speed_clamped = false;     ///< command scaled down to the speed limits
  bool tracking_clamped = false;  ///< commanded position pulled back toward the measured one
  bool limit_clamped = false;     ///< stopped at a joint limit
  bool step_clamped = false;      ///< step scaled down to the per-frame bound
};

struct JointStreamerCounters {
  std::uint64_t frames = 0;
  std::uint64_t speed_clamped = 0;
  std::uint64_t tracking_clamped = 0;
  std::uint64_t limit_clamped = 0;
  std::uint64_t step_clamped = 0;
  std::uint64_t commands = 0;  ///< velocity commands accepted
  std::uint64_t rejected_commands = 0;
  std::uint64_t rejected_states = 0;
  std::uint64_t timeouts = 0;  ///< transitions Streaming -> Holding
};

class JointPositionStreamer {
 public:
  JointPositionStreamer(const JointStreamerConfig& config, const ArmJointLimits& limits);

  /// Latest measured state (e.g. /joint_states). Names may contain extra joints (gripper) in any
  /// order; every arm joint must be present. Throws "[JointPositionStreamer] ..." on missing
  /// joints, size mismatch or non-finite values (the state is then ignored).
  void setMeasured(const std::vector<std::string>& names, const std::vector<double>& positions,
                   double now);
  /// Latest velocity command (rad/s). `names` may be empty (then command order) or must list
  /// exactly the arm joints in any order. Throws "[JointPositionStreamer] ..." on unknown or
  /// missing names, size mismatch or non-finite values (the command is then ignored).
  void setVelocityCommand(const std::vector<std::string>& names,
                          const std::vector<double>& velocities, double now);

  /// Latches the emergency stop: no frame is produced until resetEmergencyStop().
  void emergencyStop();
  /// Clears the latch; streaming restarts from the measured position on the next fresh command.
  void resetEmergencyStop();
  bool emergencyStopped() const { return phase_ == StreamPhase::EmergencyStopped; }

  /// Call once per period (rate_hz). Returns the frame to publish, or nothing (idle/stopped).
  std::optional<JointFrame> step(double now);

  StreamPhase phase() const { return phase_; }
  const JointStreamerCounters& counters() const { return counters_; }
  /// Effective per-joint speed bound (rad/s) and per-frame step bound (rad).
  const Eigen::VectorXd& speedLimit() const { return speed_limit_; }
  const Eigen::VectorXd& stepLimit() const { return step_limit_; }
  const Eigen::VectorXd& lowerLimit() const { return lower_; }
  const Eigen::VectorXd& upperLimit() const { return upper_; }
  double period() const { return 1.0 / config_.rate_hz; }
  const std::vector<std::string>& jointNames() const { return limits_.names; }
  std::string summary() const;

 private:
  [[noreturn]] void fail(const std::string& what) const;
  bool measuredFresh(double now) const;
  bool commandFresh(double now) const;

  JointStreamerConfig config_;
  ArmJointLimits limits_;
  Eigen::VectorXd lower_, upper_;  ///< limits shrunk by the margin
  Eigen::VectorXd speed_limit_, step_limit_;

  StreamPhase phase_ = StreamPhase::Idle;
  Eigen::VectorXd measured_;
  double measured_time_ = 0.0;
  bool has_measured_ = false;
  Eigen::VectorXd command_;
  double command_time_ = 0.0;
  bool has_command_ = false;
  Eigen::VectorXd last_frame_;
  double hold_start_ = 0.0;
  JointStreamerCounters counters_;
};

// ------------------------------------------------------------------ gripper requests
struct GripperConfig {
  double max_opening = 0.07;            ///< m at Gripper_Set position 1000
  std::uint16_t open_position = 1000;   ///< Gripper_Set position for "open"
  std::uint16_t close_position = 1;     ///< Gripper_Set position for "close"
  std::uint16_t pick_speed = 500;       ///< Gripper_Pick speed for "pick" (1..1000)
  std::uint16_t pick_force = 500;       ///< Gripper_Pick force for "pick" (1..1000)
  void validate() const;                ///< throws "[GripperConfig] ..."
};

struct GripperRequest {
  enum class Kind { Set, Pick } kind = Kind::Set;
  std::uint16_t position = 1;  ///< Set: 1..1000
  std::uint16_t speed = 1;     ///< Pick: 1..1000
  std::uint16_t force = 1;     ///< Pick: 1..1000
};

/// "open" | "close" | "pick" (case-insensitive, surrounding blanks ignored).
/// Throws "[GripperCommand] ..." for anything else.
GripperRequest gripperRequestFromCommand(const std::string& command, const GripperConfig& config);
/// Opening width in metres -> Gripper_Set (clamped to 1..1000). Throws on non-finite widths.
GripperRequest gripperRequestFromWidth(double width_m, const GripperConfig& config);

}  // namespace ehc_realman
