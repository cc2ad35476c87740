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
// On top of either model, the base imprecision (BaseImprecisionParams, sim.base_imprecision;
// level 0 = off): command latency, minimum speed, systematic (UMBmark) and random (slip) wheel
// errors the odometry cannot see, localisation fixes that make /odom jump; one level scales
// them together.
//
// Every Water2BaseParams field names its source; values nobody has measured are marked
// ASSUMPTION (to be identified on the robot). ROS-free.

#include "ehc_realman/water2_base_bridge.h"
#include "ehc_realman/water2_velocity_response.h"

#include <Eigen/Core>

#include <deque>
#include <utility>
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

/// Base imprecision on top of either base model (sim.base_imprecision): what makes a wheeled
/// base imprecise at close range while the stack believes its odometry. Every magnitude below is
/// the NOMINAL value (level 1); the model uses level x that value (levelled()), so one knob
/// scales them together for sweeps. level 0 = off: no effect, no random draw, today's base bit
/// for bit. The robot's odometry (/odom of the ideal model; the pose the Water2 reports in
/// robot_status) integrates the wheel velocity with the nominal kinematics (encoders); the true
/// pose moves with the erroneous kinematics and the slip, which the odometry cannot see, and a
/// localisation fix resets the odometry to the true pose (plus its error) every
/// localisation_period: /odom jumps. Error model of a differential drive after Borenstein & Feng,
/// "Measurement and correction of systematic odometry errors in mobile robots", IEEE Trans.
/// Robotics and Automation 12(6), 1996 (UMBmark): scale error E_s (mean wheel diameter), unequal
/// wheel diameters E_d (a straight command curves: heading drift (E_d - 1) / track per metre)
/// and effective track E_b (turns scaled by 1 / E_b); non-systematic errors (slip) on top.
/// Magnitudes nobody measured on this robot are marked ASSUMPTION. All randomness comes from the
/// run's seed (reset()): the per-run errors are unit normals drawn from it times level x sigma,
/// so runs of one seed at different levels have the same error directions.
struct BaseImprecisionParams {
  /// The knob: 0 = off; 1 = the nominal values below; k = each magnitude x k (the
  /// localisation period too: k = 2 corrects half as often). In [0, 100].
  double level = 0.0;
  // ---- systematic, drawn once per run from the seed (sigma of a zero-mean normal) ----
  /// E_s - 1: true / reported distance. ASSUMPTION (per-cent level, the order UMBmark finds
  /// on uncalibrated vehicles; not measured on the Water2).
  double scale_error = 0.02;
  /// E_b - 1: effective / nominal track; true turn = reported turn / E_b. ASSUMPTION (idem).
  double track_error = 0.02;
  /// rad/m: heading drift per metre of straight travel, (E_d - 1) / track (e.g. E_d - 1 =
  /// 0.4 % on a 0.4 m track = 0.01 rad/m). ASSUMPTION (idem).
  double curvature_error = 0.01;
  // ---- random, per step: wheel slip (first-order Gauss-Markov, correlated over time) ----
  /// Relative slip of the translation / rotation (true = reported x (1 + slip)), stationary
  /// sigma. ASSUMPTION (indoor floor; turning on the spot slips more than driving).
  double slip_linear = 0.02;
  double slip_angular = 0.05;
  /// s: correlation time of the slip (NOT scaled by level: the process's time scale).
  /// ASSUMPTION.
  double slip_correlation_time = 0.5;
  // ---- seen by the odometry too (the wheels really do it) ----
  /// m/s, rad/s: minimum speed; a base command with |v| below this and |w| below its band is
  /// not executed (the larger of this and ActuationNoise's deadband applies). ASSUMPTION
  /// (static friction of a loaded chassis; the Water2 data sheet gives no minimum speed).
  double min_linear_speed = 0.02;
  double min_angular_speed = 0.05;
  /// s from /cmd_vel to the base model (on top of the Water2 chain's own latency). ASSUMPTION
  /// (a ROS base driver and its serial or TCP link, 100 ms order; not measured).
  double command_latency = 0.1;
  // ---- localisation ----
  /// s between localisation fixes, each resetting the odometry to the true pose plus a normal
  /// error; 0 = no fixes (odometry only: the drift grows without bound). Scaled by level: a
  /// higher level corrects less often. ASSUMPTION (AMCL's defaults update the filter after
  /// 0.2 m or 30 deg of travel (ROS wiki amcl: update_min_d, update_min_a): about every 0.5-1 s
  /// for a base at 0.2-0.5 m/s).
  double localisation_period = 1.0;
  /// m, rad: sigma of a fix's error (per axis; heading). ASSUMPTION (lidar localisation, cm).
  double localisation_position_sigma = 0.01;
  double localisation_heading_sigma = 0.01;

  bool enabled() const { return level > 0.0; }
  /// The values the model uses: every field x level (slip_correlation_time unchanged; level 1).
  BaseImprecisionParams levelled() const;
  void validate() const;  ///< throws "[BaseImprecisionParams] ..."
  std::string summary() const;  ///< one line: "off" or the level and the levelled values
};

/// sim.base_model + sim.water2 + sim.base_imprecision of FakeRobotConfig.
struct BaseModelConfig {
  BaseModelType type = BaseModelType::Ideal;
  Water2BaseParams water2;  ///< used when type == Water2
  BaseImprecisionParams imprecision;  ///< on top of either model; level 0 = off
  void validate() const {
    water2.validate();
    imprecision.validate();
  }
  std::string summary() const;  ///< one line ("ideal" or the Water2 parameters; the imprecision when on)
};

/// The `water2` mapping (every key optional; unknown keys are errors naming file and field).
Water2BaseParams loadWater2BaseParams(const ehc_common::ConfigNode& n);
/// The `base_imprecision` mapping (every key optional; unknown keys are errors naming file and
/// field; NaN and out-of-range values too).
BaseImprecisionParams loadBaseImprecisionParams(const ehc_common::ConfigNode& n);

/// The pose (x, y, yaw) after moving with the constant body twist (v_x, v_y, w_z) for dt: the
/// exact SE(2) exponential. The one integration of a planar base (true pose and odometry).
Eigen::Vector3d integrateBaseTwist(const Eigen::Vector3d& pose, double vx, double vy, double wz, double dt);

/// The base imprecision of BaseImprecisionParams, stepped by KinematicFakeRobot (only when
/// enabled): delays the base command, raises the deadband, turns the wheel (odometry) twist into
/// the true one, and keeps the odometry pose with its localisation fixes.
class BaseImprecision {
 public:
  explicit BaseImprecision(const BaseImprecisionParams& params);  ///< validates; needs level > 0

  /// At `pose` (odometry = truth), time 0; draws the run's systematic errors from `seed`.
  void reset(const Eigen::Vector3d& pose, unsigned seed);
  /// The base command (nb entries) given at `now`; returns the one the base executes now: the
  /// latest command given at least command_latency ago (zero before the first).
  Eigen::VectorXd delayCommand(const Eigen::VectorXd& base_command, double now);
  double deadbandLinear(double actuation_deadband) const;   ///< the larger of the two
  double deadbandAngular(double actuation_deadband) const;
  /// The true body twist (v_x, v_y, w_z) of the wheel twist over the next dt (advances the slip),
  /// and integrates the odometry with the wheel twist.
  Eigen::Vector3d trueTwist(const Eigen::Vector3d& wheel_twist, double dt);
  /// End of a step at `now`: a localisation fix when due (odometry = true pose + error).
  void observe(const Eigen::Vector3d& true_pose, double now);

  const Eigen::Vector3d& odometryPose() const { return odometry_; }
  const Eigen::Vector3d& odometryTwist() const { return odometry_twist_; }
  long fixes() const { return fixes_; }  ///< localisation fixes since reset
  /// The run's systematic errors: E_s - 1, E_b - 1, curvature (rad/m).
  Eigen::Vector3d systematicErrors() const { return Eigen::Vector3d(scale_, track_, curvature_); }
  const BaseImprecisionParams& params() const { return params_; }  ///< as given
  const BaseImprecisionParams& levelled() const { return eff_; }   ///< as used

 private:
  BaseImprecisionParams params_, eff_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> gauss_{0.0, 1.0};
  std::deque<std::pair<double, Eigen::VectorXd>> commands_;  ///< (due, base command)
  Eigen::VectorXd in_force_;
  double scale_ = 0.0, track_ = 0.0, curvature_ = 0.0;
  Eigen::Vector2d slip_ = Eigen::Vector2d::Zero();  ///< linear, angular
  Eigen::Vector3d odometry_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d odometry_twist_ = Eigen::Vector3d::Zero();
  double next_fix_ = 0.0;
  long fixes_ = 0;
};

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
