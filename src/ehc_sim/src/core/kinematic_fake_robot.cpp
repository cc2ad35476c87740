#include "ehc_sim/kinematic_fake_robot.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace ehc_sim {

namespace {
[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("[KinematicFakeRobot] " + what);
}
}  // namespace

void ActuationNoise::validate() const {
  for (double s : {base_translation, base_rotation, arm})
    if (!std::isfinite(s) || s < 0.0 || s > 1.0)
      throw std::invalid_argument("[ActuationNoise] noise sigmas must be in [0, 1]");
  for (double d : {base_deadband_linear, base_deadband_angular})
    if (!std::isfinite(d) || d < 0.0 || d > 0.5)
      throw std::invalid_argument("[ActuationNoise] base deadbands must be in [0, 0.5]");
}

KinematicFakeRobot::KinematicFakeRobot(const ehc_control::RobotConfig& robot,
                                       const ActuationNoise& noise, unsigned seed,
                                       const BaseModelConfig& base_model)
    : robot_(robot), noise_(noise), base_model_(base_model), vmax_(robot.velocityLimits()) {
  robot_.validate();
  noise_.validate();
  base_model_.validate();
  if (base_model_.type == BaseModelType::Water2) {
    if (robot_.base_type == ehc_control::BaseType::Holonomic)
      fail("base model water2 needs a differential base (the Water2 is one)");
    // The bridge's bounds, tightened by the robot's base limits (as Water2BridgeConfig's robot_file).
    Water2BaseParams p = base_model_.water2;
    p.max_linear_velocity = std::min(p.max_linear_velocity, vmax_[0]);
    p.max_angular_velocity = std::min(p.max_angular_velocity, vmax_[robot_.nBase() - 1]);
    water2_.emplace(p);
  }
  if (base_model_.imprecision.enabled()) imprecision_.emplace(base_model_.imprecision);
  reset(Eigen::Vector3d::Zero(), robot_.arm_ready, seed);
}

void KinematicFakeRobot::reset(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q,
                               unsigned seed) {
  if (!base_pose.allFinite()) fail("reset: base pose must be finite");
  if (q.size() != robot_.nArm() || !q.allFinite())
    fail("reset: need " + std::to_string(robot_.nArm()) + " finite arm joint positions");
  base_ = base_pose;
  if (water2_) water2_->reset(base_pose);
  if (imprecision_) imprecision_->reset(base_pose, seed);
  q_ = q.cwiseMax(robot_.arm_lower).cwiseMin(robot_.arm_upper);
  executed_ = Eigen::VectorXd::Zero(nDof());
  rng_.seed(seed);
  gauss_.reset();
  time_ = 0.0;
  saturated_ = clamps_ = 0;
}

void KinematicFakeRobot::step(const Eigen::VectorXd& command, double dt) {
  if (command.size() != nDof())
    fail("command has " + std::to_string(command.size()) + " entries, expected " +
         std::to_string(nDof()));
  if (!command.allFinite()) fail("command contains NaN or Inf");
  if (!(dt > 0.0) || !std::isfinite(dt)) fail("dt must be > 0");

  const int nb = robot_.nBase();
  const bool holonomic = robot_.base_type == ehc_control::BaseType::Holonomic;
  Eigen::VectorXd v = command;
  // Base imprecision: the base executes the command given command_latency ago; a larger deadband.
  if (imprecision_) v.head(nb) = imprecision_->delayCommand(command.head(nb), time_);
  const double deadband_linear =
      imprecision_ ? imprecision_->deadbandLinear(noise_.base_deadband_linear) : noise_.base_deadband_linear;
  const double deadband_angular =
      imprecision_ ? imprecision_->deadbandAngular(noise_.base_deadband_angular) : noise_.base_deadband_angular;
  const Eigen::VectorXd to_base = v;  // unsaturated: the Water2 bridge scales it itself
  if ((v.array().abs() > vmax_.array()).any()) ++saturated_;
  v = v.cwiseMax(-vmax_).cwiseMin(vmax_);

  bool base_moves;
  if (water2_) {
    // The unsaturated command goes to the bridge, which scales it keeping the turn radius; the
    // wheels execute what the chain makes of it (nb == 2: the Water2 is differential).
    if (water2_->bridgeBypassed()) {
      if (command[0] != 0.0 || command[nb - 1] != 0.0)
        fail("the base takes joy_controls over its API (joyControlReceived): the step's base command must be zero");
    } else {
      water2_->command(to_base[0], to_base[nb - 1], time_);
    }
    const Eigen::Vector2d wheel = water2_->advance(time_, dt, deadband_linear, deadband_angular);
    v[0] = wheel[0];
    v[nb - 1] = wheel[1];
    base_moves = !wheel.isZero(0.0);
  } else {
    base_moves = std::abs(v[0]) >= deadband_linear || (holonomic && std::abs(v[1]) >= deadband_linear) ||
                 std::abs(v[nb - 1]) >= deadband_angular;
  }
  const bool arm_moves = !v.tail(robot_.nArm()).isZero(0.0);
  if (!base_moves) v.head(nb).setZero();
  if (noise_.enabled && base_moves) {
    v[0] += noise_.base_translation * gauss_(rng_);
    if (holonomic) v[1] += noise_.base_translation * gauss_(rng_);
    v[nb - 1] += noise_.base_rotation * gauss_(rng_);
  }
  if (noise_.enabled && arm_moves)
    for (int i = nb; i < v.size(); ++i) v[i] += noise_.arm * gauss_(rng_);

  // Base: exact SE(2) exponential of the constant body twist (v_x, v_y, w_z) over dt. With the
  // base imprecision this is the wheels' (odometry's) twist; the base moves with the true one.
  Eigen::Vector3d twist(v[0], holonomic ? v[1] : 0.0, v[nb - 1]);
  if (imprecision_) {
    twist = imprecision_->trueTwist(twist, dt);
    v[0] = twist[0];
    if (holonomic) v[1] = twist[1];
    v[nb - 1] = twist[2];
  }
  base_ = integrateBaseTwist(base_, twist[0], twist[1], twist[2], dt);

  // Arm: integrate, clamp to the joint limits, report the rate actually executed.
  const Eigen::VectorXd q_new = q_ + v.tail(robot_.nArm()) * dt;
  const Eigen::VectorXd q_clamped = q_new.cwiseMax(robot_.arm_lower).cwiseMin(robot_.arm_upper);
  if (!q_clamped.isApprox(q_new, 0.0)) ++clamps_;
  v.tail(robot_.nArm()) = (q_clamped - q_) / dt;
  q_ = q_clamped;
  executed_ = v;
  time_ += dt;
  if (imprecision_) imprecision_->observe(base_, time_);
  // The Water2's robot_status reports the base's own (odometry + localisation) pose.
  if (water2_) water2_->observe(imprecision_ ? imprecision_->odometryPose() : base_, time_, rng_, gauss_);
}

void KinematicFakeRobot::joyControlReceived(double linear, double angular) {
  if (!water2_) fail("joy_control needs the water2 base model (sim.base_model: water2)");
  // The base imprecision's latency on top of the connection's own.
  water2_->joyControlReceived(linear, angular, time_ + (imprecision_ ? imprecision_->levelled().command_latency : 0.0));
}

Eigen::Vector3d KinematicFakeRobot::statusPose() const {
  if (!water2_) fail("robot_status needs the water2 base model (sim.base_model: water2)");
  return water2_->statusPose(imprecision_ ? imprecision_->odometryPose() : base_);
}

Eigen::Vector3d KinematicFakeRobot::odometryPose() const {
  if (water2_) return water2_->odometry(time_).pose;
  return imprecision_ ? imprecision_->odometryPose() : base_;
}

Eigen::Vector3d KinematicFakeRobot::odometryTwist() const {
  const int nb = robot_.nBase();
  if (water2_) {
    const BaseOdometryEstimate o = water2_->odometry(time_);
    return Eigen::Vector3d(o.linear, 0.0, o.angular);
  }
  if (imprecision_) return imprecision_->odometryTwist();
  return Eigen::Vector3d(executed_[0], nb == 3 ? executed_[1] : 0.0, executed_[nb - 1]);
}

}  // namespace ehc_sim
