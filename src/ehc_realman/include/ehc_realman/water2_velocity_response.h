#pragma once
// Water2VelocityResponse (ROS-free): how the Water2 base executes the joy_controls it receives,
// the one home of this model. Used by
//   - ehc_sim::Water2BaseModel (both simulators and the hardware stand-in): the simulated base's
//     wheel velocity;
//   - ehc_realman::OdometryEstimator (water2_base_bridge): the bridge dead-reckons between two
//     robot_status poses with the velocity this model predicts from the joy_controls it sent,
//     not with the commanded velocity (which the base reaches only after latency, lag and an
//     acceleration ramp, and then times its gain).
//
// Chain: a joy_control sent at t is executed from t + command_latency, for command_lifetime
// unless renewed (zero afterwards); the velocity loop moves each wheel velocity (v, w) towards
// gain x command, first-order with time_constant, each change bounded by the acceleration limit.
// Every default names its source; ASSUMPTION = not measured on the robot (to be identified).

#include <Eigen/Core>

#include <deque>
#include <string>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_realman {

struct Water2ResponseParams {
  /// s a joy_control is executed unless renewed (REALMAN.md, DESIGN.md §12: 0.5 s).
  double command_lifetime = 0.5;
  /// s from sending a joy_control to the wheels acting on it. ASSUMPTION (TCP on the robot's
  /// LAN + one firmware cycle; not measured).
  double command_latency = 0.05;
  /// m/s^2, rad/s^2: acceleration limits of the velocity loop. ASSUMPTION (typical of indoor
  /// service-robot chassis; the Water2 data sheet gives none). May be +inf (no limit).
  double linear_acceleration = 0.5;
  double angular_acceleration = 1.0;
  /// s: time constant of the first-order velocity loop (0 = none). ASSUMPTION.
  double time_constant = 0.1;
  /// Executed / commanded velocity in steady state (load, wheel radius and track calibration).
  /// ASSUMPTION (a few per cent).
  double linear_gain = 0.95;
  double angular_gain = 0.95;

  /// The base executes each command at once and exactly (no latency, lag, ramp or gain error):
  /// dead reckoning with the commanded velocity (a bridge without a response model); also
  /// what a base that follows commands ideally (the loopback tests' fake server) does.
  static Water2ResponseParams commandedVelocity();

  /// Throws "[<owner>] <field_prefix><field> ...".
  void validate(const std::string& owner, const std::string& field_prefix = "") const;
  std::string summary() const;                    ///< one line
};

/// Reads the keys above from `n` when present (defaults otherwise). Unknown keys are left to
/// the caller's rejectUnknownKeys() (the sim reads them from its flat `water2` mapping, the
/// bridge from `water2_base_bridge.base_response`).
void readWater2ResponseParams(const ehc_common::ConfigNode& n, Water2ResponseParams* params);

class Water2VelocityResponse {
 public:
  explicit Water2VelocityResponse(const Water2ResponseParams& params);  ///< validates

  /// At rest, nothing in flight.
  void reset();
  /// A joy_control sent at `sent`: executed from sent + command_latency.
  void joyControlSent(double linear, double angular, double sent);
  /// A joy_control the base executes from `at` (its latency already elapsed, e.g. a real TCP
  /// connection delivered it). Calls must come in non-decreasing `at` order.
  void joyControlAt(double linear, double angular, double at);
  /// Wheel velocity (v, w) over [now, now + dt): takes the joy_control in force at `now` (zero
  /// once its lifetime is over; zero when both components are inside the deadband: static
  /// friction) and moves the velocity loop towards gain x command, acceleration-limited. A wheel
  /// told to stop stops below its deadband.
  Eigen::Vector2d advance(double now, double dt, double deadband_linear = 0.0, double deadband_angular = 0.0);

  /// The joy_control in force at the last advance() (zero if none).
  const Eigen::Vector2d& commandInForce() const { return in_force_; }
  const Eigen::Vector2d& wheelVelocity() const { return wheel_; }
  const Water2ResponseParams& params() const { return params_; }
  std::size_t inFlight() const { return in_flight_.size(); }

 private:
  struct Timed {
    double at;  ///< s: when the base starts executing it
    Eigen::Vector2d twist;
  };
  Water2ResponseParams params_;
  std::deque<Timed> in_flight_;
  Eigen::Vector2d held_ = Eigen::Vector2d::Zero();
  double held_until_ = -1.0;  ///< s
  Eigen::Vector2d in_force_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d wheel_ = Eigen::Vector2d::Zero();
};

}  // namespace ehc_realman
