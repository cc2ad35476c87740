#pragma once
// Base models of the fake robots (KinematicFakeRobot, hence both simulators and the Exp-1
// runner): how the simulated base executes a /cmd_vel command and what /odom reports.
//
//   ideal   the command is executed at once (velocity limits, Table I noise, deadband of
//           ActuationNoise); /odom is the true pose. Today's behaviour, bit for bit.
//   water2  the RealMan Water2 chain (REALMAN.md, DESIGN.md §12), with the bridge's own core
//           classes (ehc_realman::BaseCommandWatchdog, OdometryEstimator):
//           /cmd_vel -> bridge (scales into |V| <= 0.5 m/s, |W| <= 1 rad/s keeping the turn
//           radius; resends the latest command at 20 Hz; zero once /cmd_vel stops for 0.2 s)
//           -> ehc_realman::Water2VelocityResponse (command latency, the firmware executes each
//           joy_control for 0.5 s unless renewed, velocity loop: first-order lag, acceleration
//           limits, gain error; Table I noise on top) -> wheels. robot_status: the base's map
//           pose (REALMAN.md: "the pose in robot_status is the base's map pose") with a slowly
//           varying localisation error, sampled every 0.5 s and received after a status
//           latency; /odom is the bridge's estimate: the latest status (valid at its sample
//           time) dead-reckoned with the velocity the same response model predicts.
//
// Every Water2BaseParams field names its source; values nobody has measured are marked
// ASSUMPTION (to be identified on the robot). ROS-free.

#include "ehc_realman/water2_base_bridge.h"
#include "ehc_realman/water2_velocity_response.h"

#include <Eigen/Core>

#include <deque>
#include <optional>
#include <random>
#include <string>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_sim {

enum class BaseModelType { Ideal, Water2 };
std::string toString(BaseModelType type);
/// "ideal" | "water2"; throws std::invalid_argument "[BaseModel] unknown base model ...".
BaseModelType baseModelTypeFromString(const std::string& name);

struct Water2BaseParams {
  // ---- the bridge (water2_base_bridge: Water2BridgeConfig defaults, REALMAN.md) ----
  /// m/s and rad/s: joy_control bounds (REALMAN.md, DESIGN.md §12); the bridge scales a faster
  /// command down as a whole (keeps the turn radius). The robot.yaml base limits tighten them.
  double max_linear_velocity = ehc_realman::Water2BridgeConfig().max_linear_velocity;    // 0.5
  double max_angular_velocity = ehc_realman::Water2BridgeConfig().max_angular_velocity;  // 1.0
  /// Hz: the bridge resends the latest fresh command at this rate (REALMAN.md: 20 Hz).
  double resend_rate = ehc_realman::Water2BridgeConfig().resend_rate_hz;
  /// s without /cmd_vel after which the bridge sends zero (Water2BridgeConfig::command_timeout).
  double bridge_command_timeout = ehc_realman::Water2BridgeConfig().command_timeout;
  /// s between robot_status requests (REALMAN.md: every 0.5 s, i.e. ~2 Hz odometry).
  double status_period = ehc_realman::Water2BridgeConfig().status_period;
  /// s the bridge dead-reckons past the last status (REALMAN.md: at most 0.6 s).
  double max_extrapolation = ehc_realman::Water2BridgeConfig().max_extrapolation;

  // ---- the base (Water2 firmware and wheels) ----
  /// The velocity response (latency, 0.5 s hold, velocity loop, acceleration limits, gain):
  /// ehc_realman::Water2ResponseParams, whose defaults name their sources and ASSUMPTIONS. The
  /// modelled bridge dead-reckons through the same model and values (the bridge's base_response
  /// defaults are these).
  ehc_realman::Water2ResponseParams response;
  /// What the modelled bridge believes the response is (its base_response), when it differs
  /// from `response`: a mis-identified model, or Water2ResponseParams::commandedVelocity() for
  /// a bridge that dead-reckons with the commanded twist. Unset = `response`.
  std::optional<ehc_realman::Water2ResponseParams> bridge_response;
  /// s from the base sampling its pose to the bridge receiving the robot_status reply.
  /// ASSUMPTION (not measured). The bridge takes the pose as valid when it sent the request
  /// (not when it reads the reply), i.e. at the sample time here.
  double status_latency = 0.05;
  /// Error of the robot_status map pose: first-order Gauss-Markov per axis (x, y, heading) with
  /// this stationary sigma and correlation time, zero at reset. ASSUMPTION (lidar localisation;
  /// 0 = the status pose is the true pose).
  double localisation_position_sigma = 0.002;  ///< m
  double localisation_heading_sigma = 0.002;   ///< rad
  double localisation_correlation_time = 5.0;  ///< s

  const ehc_realman::Water2ResponseParams& bridgeResponse() const { return bridge_response ? *bridge_response : response; }

  void validate() const;  ///< throws "[Water2BaseParams] ..."
  std::string summary() const;
};

/// sim.base_model + sim.water2 of FakeRobotConfig.
struct BaseModelConfig {
  BaseModelType type = BaseModelType::Ideal;
  Water2BaseParams water2;  ///< used when type == Water2
  void validate() const { water2.validate(); }
  std::string summary() const;  ///< one line ("ideal" or the Water2 parameters)
};

/// The `water2` mapping (every key optional; unknown keys are errors naming file and field).
Water2BaseParams loadWater2BaseParams(const ehc_common::ConfigNode& n);

/// What the bridge publishes on /odom: pose in odom (x, y, yaw), the predicted base velocity.
struct BaseOdometryEstimate {
  Eigen::Vector3d pose = Eigen::Vector3d::Zero();
  double linear = 0.0;   ///< m/s, base frame
  double angular = 0.0;  ///< rad/s
};

/// The Water2 chain of the file comment, stepped on sim time by KinematicFakeRobot: command()
/// at the start of a step, advance() for the wheel velocity over the step, observe() with the
/// true pose at its end, odometry() for /odom.
class Water2BaseModel {
 public:
  explicit Water2BaseModel(const Water2BaseParams& params);

  /// At rest at `pose`, time 0; the bridge has the status of `pose` (it connected before).
  void reset(const Eigen::Vector3d& pose);

  /// The controller's /cmd_vel (v, w) at `now`, into the bridge. True if the bridge scaled it.
  bool command(double linear, double angular, double now);
  /// One joy_control leaving the bridge at `sent` (the bridge's sends come through here; tests
  /// call it directly to see the base without the bridge). Executed from sent + latency.
  void joyControl(double linear, double angular, double sent);

  /// A joy_control the base receives over its own API at `now` (the hardware stand-in: the real
  /// water2_base_bridge sends it over TCP, so its latency is real). From the first one on the
  /// modelled bridge is out of the chain: command() must not be called, advance() sends nothing.
  void joyControlReceived(double linear, double angular, double now);
  bool bridgeBypassed() const { return bridge_bypassed_; }
  /// What robot_status reports now: the true pose plus the current localisation error.
  Eigen::Vector3d statusPose(const Eigen::Vector3d& true_pose) const;

  /// Wheel velocity (v, w) over [now, now + dt): sends what the bridge has due at `now`, takes
  /// the joy_control in force (zero once its lifetime is over; zero inside the deadband) and
  /// moves the velocity loop towards gain x command, acceleration-limited. A wheel that is
  /// told to stop stops below its deadband (static friction).
  Eigen::Vector2d advance(double now, double dt, double deadband_linear, double deadband_angular);

  /// The true pose at `now` (end of a step): samples robot_status when due (true pose +
  /// localisation error drawn from `gauss`) and hands the bridge every reply received by now.
  void observe(const Eigen::Vector3d& true_pose, double now, std::mt19937_64& rng,
               std::normal_distribution<double>& gauss);

  /// The bridge's /odom at `now`. Throws "[Water2BaseModel] ..." if the bridge has no fresh
  /// status (cannot happen while observe() is called every step).
  BaseOdometryEstimate odometry(double now) const;

  /// The joy_control in force at the last advance() (zero if none), m/s and rad/s.
  const Eigen::Vector2d& commandInForce() const { return response_.commandInForce(); }
  const Eigen::Vector2d& wheelVelocity() const { return response_.wheelVelocity(); }
  long joyControls() const { return joy_controls_; }  ///< sent since reset
  long statuses() const { return statuses_; }          ///< robot_status replies received since reset
  const Water2BaseParams& params() const { return params_; }

 private:
  struct TimedPose {
    double at;              ///< s: when the bridge receives it
    double valid;           ///< s: when the bridge's request was sent (the base sampled it)
    Eigen::Vector3d value;  ///< (x, y, yaw)
  };
  Water2BaseParams params_;
  ehc_realman::BaseCommandWatchdog bridge_;
  ehc_realman::OdometryEstimator estimator_;
  ehc_realman::Water2VelocityResponse response_;
  std::deque<TimedPose> statuses_in_flight_;
  Eigen::Vector3d localisation_error_ = Eigen::Vector3d::Zero();
  double next_status_sample_ = 0.0;  ///< s
  long joy_controls_ = 0, statuses_ = 0;
  bool bridge_bypassed_ = false;  ///< joy_controls come from outside (joyControlReceived)
};

}  // namespace ehc_sim
