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
  reset(Eigen::Vector3d::Zero(), robot_.arm_ready, seed);
}

void KinematicFakeRobot::reset(const Eigen::Vector3d& base_pose, const Eigen::VectorXd& q,
                               unsigned seed) {
  if (!base_pose.allFinite()) fail("reset: base pose must be finite");
  if (q.size() != robot_.nArm() || !q.allFinite())
    fail("reset: need " + std::to_string(robot_.nArm()) + " finite arm joint positions");
  base_ = base_pose;
  if (water2_) water2_->reset(base_pose);
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

  Eigen::VectorXd v = command;
  if ((v.array().abs() > vmax_.array()).any()) ++saturated_;
  v = v.cwiseMax(-vmax_).cwiseMin(vmax_);

  const int nb = robot_.nBase();
  const bool holonomic = robot_.base_type == ehc_control::BaseType::Holonomic;
  bool base_moves;
  if (water2_) {
    // The unsaturated command goes to the bridge, which scales it keeping the turn radius; the
    // wheels execute what the chain makes of it (nb == 2: the Water2 is differential).
    if (water2_->bridgeBypassed()) {
      if (command[0] != 0.0 || command[nb - 1] != 0.0)
        fail("the base takes joy_controls over its API (joyControlReceived): the step's base command must be zero");
    } else {
      water2_->command(command[0], command[nb - 1], time_);
    }
    const Eigen::Vector2d wheel = water2_->advance(time_, dt, noise_.base_deadband_linear,
                                                   noise_.base_deadband_angular);
    v[0] = wheel[0];
    v[nb - 1] = wheel[1];
    base_moves = !wheel.isZero(0.0);
  } else {
    base_moves = std::abs(v[0]) >= noise_.base_deadband_linear ||
                 (holonomic && std::abs(v[1]) >= noise_.base_deadband_linear) ||
                 std::abs(v[nb - 1]) >= noise_.base_deadband_angular;
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

  // Base: exact SE(2) exponential of the constant body twist (v_x, v_y, w_z) over dt.
  const double vx = v[0], vy = holonomic ? v[1] : 0.0, wz = v[nb - 1];
  const double th = wz * dt;
  double dx, dy;
  if (std::abs(th) < 1e-9) {
    dx = vx * dt - 0.5 * vy * th * dt;
    dy = vy * dt + 0.5 * vx * th * dt;
  } else {
    const double s = std::sin(th) / wz, c = (1.0 - std::cos(th)) / wz;
    dx = s * vx - c * vy;
    dy = c * vx + s * vy;
  }
  const double cy = std::cos(base_.z()), sy = std::sin(base_.z());
  base_.x() += cy * dx - sy * dy;
  base_.y() += sy * dx + cy * dy;
  base_.z() = std::remainder(base_.z() + th, 2.0 * M_PI);

  // Arm: integrate, clamp to the joint limits, report the rate actually executed.
  const Eigen::VectorXd q_new = q_ + v.tail(robot_.nArm()) * dt;
  const Eigen::VectorXd q_clamped = q_new.cwiseMax(robot_.arm_lower).cwiseMin(robot_.arm_upper);
  if (!q_clamped.isApprox(q_new, 0.0)) ++clamps_;
  v.tail(robot_.nArm()) = (q_clamped - q_) / dt;
  q_ = q_clamped;
  executed_ = v;
  time_ += dt;
  if (water2_) water2_->observe(base_, time_, rng_, gauss_);
}

void KinematicFakeRobot::joyControlReceived(double linear, double angular) {
  if (!water2_) fail("joy_control needs the water2 base model (sim.base_model: water2)");
  water2_->joyControlReceived(linear, angular, time_);
}

Eigen::Vector3d KinematicFakeRobot::statusPose() const {
  if (!water2_) fail("robot_status needs the water2 base model (sim.base_model: water2)");
  return water2_->statusPose(base_);
}

Eigen::Vector3d KinematicFakeRobot::odometryPose() const {
  return water2_ ? water2_->odometry(time_).pose : base_;
}

Eigen::Vector3d KinematicFakeRobot::odometryTwist() const {
  const int nb = robot_.nBase();
  if (water2_) {
    const BaseOdometryEstimate o = water2_->odometry(time_);
    return Eigen::Vector3d(o.linear, 0.0, o.angular);
  }
  return Eigen::Vector3d(executed_[0], nb == 3 ? executed_[1] : 0.0, executed_[nb - 1]);
}

}  // namespace ehc_sim
