#include "ehc_control/controller_supervisor.h"

#include "ehc_common/config_node.h"
#include "ehc_control/joint_state.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

using ehc_common::requireRange;

namespace ehc_control {

void SupervisorParams::validate() const {
  requireRange("SupervisorParams", "state_timeout", state_timeout, 1e-3, 10.0);
  requireRange("SupervisorParams", "target_timeout", target_timeout, 1e-3, 60.0);
  requireRange("SupervisorParams", "obstacle_timeout", obstacle_timeout, 1e-3, 60.0);
  requireRange("SupervisorParams", "max_solve_time", max_solve_time, 1e-6, 1.0);
}

std::string SupervisorParams::summary() const {
  std::ostringstream os;
  os << "watchdog: state " << state_timeout << " s, target " << target_timeout << " s, obstacles "
     << obstacle_timeout << " s (" << (require_obstacles ? "required: missing or stale -> OBSTACLES_STALE"
                                                         : "optional: tracks without when stale")
     << "), receipt times on this node's clock; cycle budget " << max_solve_time * 1e3 << " ms";
  return os.str();
}

namespace {
/// Missing, older than `timeout`, or from the future by more than `timeout` (a clock jump).
bool isStale(const std::optional<double>& t, double now, double timeout) {
  return !t || now - *t > timeout || now - *t < -timeout;
}
}  // namespace

SupervisorParams loadSupervisorParams(const ehc_common::ConfigNode& n) {
  SupervisorParams p;
  p.state_timeout = n.get("state_timeout", p.state_timeout);
  p.target_timeout = n.get("target_timeout", p.target_timeout);
  p.obstacle_timeout = n.get("obstacle_timeout", p.obstacle_timeout);
  p.require_obstacles = n.get("require_obstacles", p.require_obstacles);
  p.max_solve_time = n.get("max_solve_time", p.max_solve_time);
  n.validate(p);  // errors name the file and the section
  return p;
}

ControllerSupervisor::ControllerSupervisor(const RobotConfig& robot, const SupervisorParams& params)
    : robot_(robot), params_(params), q_(robot.arm_ready) {
  robot_.validate();
  params_.validate();
}

std::string ControllerSupervisor::setJointState(double t, const std::vector<std::string>& names,
                                                const std::vector<double>& positions) {
  const std::string why = armPositionsFromJointState(robot_.arm_joints, names, positions, &q_);
  if (!why.empty()) {
    ++rejected_;
    return why;
  }
  t_joints_ = t;
  return "";
}

std::string ControllerSupervisor::setBasePose(double t, const Eigen::Vector3d& base) {
  if (!base.allFinite()) {
    ++rejected_;
    return "odometry contains NaN or Inf";
  }
  base_ = base;
  t_base_ = t;
  return "";
}

std::string ControllerSupervisor::setTarget(double t, const Eigen::Isometry3d& target) {
  if (!target.matrix().allFinite()) {
    ++rejected_;
    return "target pose contains NaN or Inf";
  }
  const double det = target.linear().determinant();
  if (std::abs(det - 1.0) > 1e-3) {
    ++rejected_;
    return "target orientation is not a rotation (bad quaternion)";
  }
  target_ = target;
  t_target_ = t;
  return "";
}

std::string ControllerSupervisor::setObstacles(double t, const std::vector<ObstaclePair>& obstacles) {
  for (const auto& o : obstacles)
    if (!std::isfinite(o.distance) || !o.link_point.allFinite() || !o.obstacle_point.allFinite() ||
        !o.normal.allFinite() || o.normal.norm() < 1e-9) {
      ++rejected_;
      return "obstacle list contains a non-finite or zero-normal pair (link '" + o.link + "')";
    }
  obstacles_ = obstacles;
  t_obstacles_ = t;
  return "";
}

void ControllerSupervisor::clearTarget() { t_target_.reset(); }

SupervisorDecision ControllerSupervisor::check(double now) const {
  SupervisorDecision d;
  auto stale = [&](const std::optional<double>& t, double timeout) { return isStale(t, now, timeout); };
  std::ostringstream why;
  if (!t_joints_) why << "no joint state yet; ";
  else if (stale(t_joints_, params_.state_timeout)) why << "joint state is " << now - *t_joints_ << " s old; ";
  if (!t_base_) why << "no odometry yet; ";
  else if (stale(t_base_, params_.state_timeout)) why << "odometry is " << now - *t_base_ << " s old; ";
  if (!why.str().empty()) {
    d.phase = ControlPhase::Stopped;
    d.reason = why.str().substr(0, why.str().size() - 2);
    return d;
  }
  if (params_.require_obstacles && stale(t_obstacles_, params_.obstacle_timeout)) {
    d.phase = ControlPhase::ObstaclesStale;
    std::ostringstream os;
    if (!t_obstacles_) os << "no obstacle list yet";
    else os << "obstacle list is " << now - *t_obstacles_ << " s old";
    os << " (obstacle sensing required, timeout " << params_.obstacle_timeout << " s)";
    d.reason = os.str();
    return d;
  }
  if (!t_target_) {
    d.phase = ControlPhase::Idle;
    d.reason = "no target";
    return d;
  }
  if (stale(t_target_, params_.target_timeout)) {
    d.phase = ControlPhase::TargetLost;
    std::ostringstream os;
    os << "target is " << now - *t_target_ << " s old (timeout " << params_.target_timeout << " s)";
    d.reason = os.str();
    return d;
  }
  d.run = true;
  return d;
}

double ControllerSupervisor::stateAge(double now) const {
  if (!t_joints_ || !t_base_) return -1.0;
  return now - std::min(*t_joints_, *t_base_);
}

const std::vector<ObstaclePair>& ControllerSupervisor::obstacles(double now) const {
  static const std::vector<ObstaclePair> kNone;
  if (isStale(t_obstacles_, now, params_.obstacle_timeout)) return kNone;
  return obstacles_;
}

CycleWatchdog::CycleWatchdog(double state_timeout, double wall_timeout)
    : state_timeout_(state_timeout), wall_timeout_(wall_timeout) {
  if (!(state_timeout > 0.0) || !(wall_timeout > 0.0))
    throw std::invalid_argument("[CycleWatchdog] the state and wall-clock timeouts must be > 0");
}

void CycleWatchdog::cycleRan(double ros_now, double wall_now) {
  last_cycle_ros_ = ros_now;
  last_cycle_wall_ = wall_now;
}

std::string CycleWatchdog::checkRosTime(double ros_now) const {
  if (!last_cycle_ros_) return "";
  const double idle = ros_now - *last_cycle_ros_;
  if (idle <= state_timeout_ && idle >= -state_timeout_) return "";
  std::ostringstream why;
  why << "no control cycle for " << idle << " s (lock-step: no joint state + odometry pair)";
  return why.str();
}

std::string CycleWatchdog::checkWallClock(double wall_now, double ros_now) {
  if (ros_now != last_ros_time_) {
    last_ros_time_ = ros_now;
    last_ros_advance_wall_ = wall_now;
    return "";
  }
  if (!last_cycle_wall_) return "";
  const double idle = wall_now - *last_cycle_wall_;
  const double frozen = wall_now - last_ros_advance_wall_;
  if (idle <= wall_timeout_ || frozen <= wall_timeout_) return "";
  std::ostringstream why;
  why << "no control cycle for " << idle << " wall s (ROS time " << ros_now << " stands still? simulator dead?)";
  return why.str();
}

}  // namespace ehc_control
