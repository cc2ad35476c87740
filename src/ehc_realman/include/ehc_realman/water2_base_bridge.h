#pragma once
// Water2 base bridge core (ROS-free): /cmd_vel -> joy_control over TCP with a watchdog, odometry
// from the base's robot_status replies, reconnection with back-off.
//
//  - BaseCommandWatchdog: clamps commands (uniform scaling keeps the path curvature w/v), resends
//    fresh commands at resend_rate_hz (the base executes each for 0.5 s), sends zero for
//    stop_repeat_duration once commands stop for command_timeout, then goes quiet.
//  - OdometryEstimator: pose from the latest status (~2 Hz) AT THE TIME IT WAS VALID, dead-
//    reckoned from then for at most max_extrapolation with the velocity the base is predicted to
//    execute: the twists sent, through Water2VelocityResponse (latency, 0.5 s hold, velocity
//    loop, acceleration limits, gain; base_response in the config), the model the simulators'
//    Water2 base runs. Dead reckoning with the commanded twist instead made /odom jump by up to
//    11 cm at a status in the rehearsal. No estimate once the status is older than
//    status_timeout (stale data is never published as fresh). The bridge takes a robot_status pose as valid when its
//    request was sent, not when the reply was read: a reply read late (a loaded computer, the
//    network thread descheduled) otherwise puts the base where it was up to that delay ago and
//    /odom and tf jump back by v x delay (REALMAN.md "Rehearsal").
//  - Water2BaseBridge: owns a Water2Client; spinOnce() does one bounded cycle of network work.

#include "ehc_realman/water2_client.h"
#include "ehc_realman/water2_protocol.h"
#include "ehc_realman/water2_velocity_response.h"

#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <mutex>
#include <optional>
#include <string>

namespace ehc_realman {

struct Water2BridgeConfig {
  std::string source_file;           ///< the YAML this came from ("" if built in code)
  std::string robot_file;            ///< optional robot.yaml: its base limits tighten the ones below
  std::string host = "192.168.10.10";
  int port = 31001;
  double connect_timeout = 0.5;      ///< s per connection attempt
  std::string command_terminator;    ///< appended to each request ("" as the vendor examples)
  double max_linear_velocity = 0.5;  ///< m/s   (joy_control bound)
  double max_angular_velocity = 1.0; ///< rad/s (joy_control bound)
  double resend_rate_hz = 20.0;      ///< joy_control rate while commands are fresh (>= 10)
  double command_timeout = 0.2;      ///< s without /cmd_vel => zero
  double stop_repeat_duration = 1.0; ///< s of zero commands after a timeout, then quiet
  double status_period = 0.5;        ///< s between robot_status requests
  double status_timeout = 1.5;       ///< s: older status => odometry stale (not published)
  double max_extrapolation = 0.6;    ///< s of dead reckoning past the last status
  /// How the base executes joy_controls (base_response:), for the dead reckoning. Defaults =
  /// the simulators' water2 model (mostly ASSUMPTIONS: identify them on the robot).
  Water2ResponseParams base_response;
  double reply_timeout = 2.0;        ///< s without any reply while connected => reconnect
  double backoff_initial = 0.2;      ///< s before the first reconnection attempt
  double backoff_max = 5.0;          ///< s, doubling up to this
  int max_object_bytes = 65536;      ///< longest accepted reply
  double odom_rate_hz = 50.0;        ///< /odom + tf publication rate (node)
  double status_rate_hz = 1.0;       ///< /water2/status publication rate (node)
  std::string odom_frame = "odom";
  std::string base_frame = "base_link";

  void validate() const;  ///< throws "[Water2BridgeConfig] ..."
  std::string summary() const;
};

/// Reads `water2_base_bridge:` from `path` (every key optional). Throws naming file and field.
Water2BridgeConfig loadWater2BridgeConfig(const std::string& path);

struct BaseTwist {
  double linear = 0.0;   ///< m/s
  double angular = 0.0;  ///< rad/s
};

class BaseCommandWatchdog {
 public:
  BaseCommandWatchdog(double max_linear, double max_angular, double command_timeout,
                      double resend_period, double stop_repeat_duration);
  /// Stores the clamped command; returns true if it had to be clamped.
  /// Throws std::invalid_argument "[BaseCommandWatchdog] ..." on non-finite input.
  bool setCommand(double linear, double angular, double now);
  /// The twist to send now, if one is due (rate-limited to the resend period).
  std::optional<BaseTwist> due(double now);
  /// The next due() sends zero at once (used after a reconnection).
  void requestZero();
  bool commandFresh(double now) const;
  /// Seconds until the next send could be due (0 if now; +inf if quiet).
  double timeUntilDue(double now) const;

 private:
  double max_linear_, max_angular_, command_timeout_, resend_period_, stop_repeat_duration_;
  BaseTwist command_;
  double command_time_ = -std::numeric_limits<double>::infinity();
  double last_send_time_ = -std::numeric_limits<double>::infinity();
  bool force_zero_ = false;
  bool last_sent_nonzero_ = false;
};

struct BaseOdometry {
  double x = 0.0, y = 0.0, theta = 0.0;  ///< m, m, rad (odom frame)
  double linear = 0.0, angular = 0.0;    ///< m/s, rad/s (base frame), predicted base velocity
  double status_age = 0.0;               ///< s since the status the pose is based on
  /// Variances of /odom's pose (dead reckoning: they grow with status_age): x and y,
  /// 1e-4 + (0.5 m/s * age)^2 m^2; yaw, 1e-4 + (1 rad/s * age)^2 rad^2.
  double positionVariance() const;
  double yawVariance() const;
};

class OdometryEstimator {
 public:
  /// `response`: the base's velocity response the dead reckoning predicts through
  /// (Water2ResponseParams::commandedVelocity() = the commanded twist, executed at once).
  OdometryEstimator(double status_timeout, double max_extrapolation, const Water2ResponseParams& response);
  /// A status pose valid at `valid_time` (it may be earlier than twists already sent: they are
  /// replayed from it). A pose valid before the current one, or before the predicted velocity's
  /// history (older than status_timeout), is ignored (returns false).
  bool onStatus(const Water2Pose& pose, double valid_time);
  /// A joy_control sent at `now` (the base executes it through `response`).
  void onTwistSent(const BaseTwist& twist, double now);
  /// Nothing before the first status or once the status is older than status_timeout. The
  /// twist is the predicted base velocity at min(now, status time + max_extrapolation).
  std::optional<BaseOdometry> estimate(double now) const;
  double statusAge(double now) const;  ///< +inf before the first status
  const Water2ResponseParams& response() const { return model_.params(); }

  static constexpr double kStep = 0.01;  ///< s: integration step of the predicted velocity
  /// s without a joy_control in flight after which the base is at rest (the 0.5 s hold ran out
  /// and the velocity loop settled long ago): the model jumps instead of stepping.
  static constexpr double kAtRestAfter = 30.0;

 private:
  void advanceModelTo(double t);  ///< steps model_ (no pose) from model_time_ to t

  double status_timeout_, max_extrapolation_;
  std::optional<Water2Pose> status_pose_;
  double status_time_ = 0.0;  ///< when status_pose_ was valid
  /// The predicted velocity loop at model_time_ (== status_time_ after a status; moved on to
  /// status_timeout before the latest send without statuses, so its queue stays bounded), with
  /// the twists sent since in flight.
  Water2VelocityResponse model_;
  double model_time_ = -std::numeric_limits<double>::infinity();
  double last_sent_ = -std::numeric_limits<double>::infinity();
};

struct Water2BridgeStatus {
  enum class Level { Ok, Warn, Error } level = Level::Error;
  std::string message;
  bool connected = false;
  bool status_fresh = false;
  double status_age = std::numeric_limits<double>::infinity();
  std::uint64_t connects = 0;          ///< successful connections (1 + reconnections)
  std::uint64_t connection_losses = 0; ///< established connections that were lost
  std::uint64_t failed_connects = 0;
  std::uint64_t joy_requests = 0;
  std::uint64_t status_requests = 0;
  std::uint64_t replies = 0;
  std::uint64_t malformed_replies = 0;
  std::uint64_t error_replies = 0;     ///< well-formed replies whose status is not OK
  std::uint64_t clamped_commands = 0;
  std::uint64_t commands = 0;          ///< commands accepted (clamped ones included)
  std::uint64_t rejected_commands = 0;
  std::string last_error;
};

class Water2BaseBridge {
 public:
  using Clock = std::function<double()>;  ///< monotonic seconds
  /// `clock` defaults to std::chrono::steady_clock.
  explicit Water2BaseBridge(const Water2BridgeConfig& config, Clock clock = Clock());

  /// Thread-safe. Throws std::invalid_argument on non-finite input (counted as rejected).
  void setCommand(double linear, double angular);
  /// One bounded cycle: connect when due, send joy_control / robot_status when due, read
  /// replies for at most max_wait seconds. Never throws on network or protocol errors.
  void spinOnce(double max_wait);
  /// Thread-safe; nothing when there is no fresh status.
  std::optional<BaseOdometry> odometry() const;
  Water2BridgeStatus status() const;
  const Water2BridgeConfig& config() const { return config_; }
  double now() const { return clock_(); }

 private:
  void dropConnection(const std::string& why, double now);  // call with mutex_ held
  void handleReply(const std::string& json, double now);     // call with mutex_ held

  Water2BridgeConfig config_;
  Clock clock_;
  Water2Client client_;
  mutable std::mutex mutex_;
  BaseCommandWatchdog watchdog_;
  OdometryEstimator estimator_;
  Water2BridgeStatus counters_;
  double next_connect_time_ = 0.0;
  double backoff_ = 0.0;
  double next_status_time_ = 0.0;
  double last_reply_time_ = 0.0;
  std::deque<double> status_sent_times_;  ///< robot_status requests awaiting their reply (FIFO)
};

}  // namespace ehc_realman
