#include "ehc_sim/command_gate.h"

#include <cmath>
#include <sstream>

namespace ehc_sim {

namespace {
bool overLimit(double v, double vmax) { return std::abs(v) > vmax * (1.0 + 1e-9) + 1e-12; }
}  // namespace

CommandGate::CommandGate(const ehc_control::RobotConfig& robot)
    : robot_(robot), vmax_(robot.velocityLimits()) {
  robot_.validate();
  base_ = Eigen::VectorXd::Zero(robot_.nBase());
  arm_ = Eigen::VectorXd::Zero(robot_.nArm());
}

void CommandGate::newState(std::int64_t stamp_ns) {
  stamp_ns_ = stamp_ns;
  arm_answered_ = false;
  base_since_step_ = false;
}

std::string CommandGate::onBaseTwist(double vx, double vy, double wz) {
  base_since_step_ = true;
  std::string why;
  const bool holo = robot_.base_type == ehc_control::BaseType::Holonomic;
  if (!std::isfinite(vx) || !std::isfinite(vy) || !std::isfinite(wz))
    why = "base twist contains NaN or Inf";
  else if (!holo && vy != 0.0)
    why = "linear.y must be 0 for a differential base";
  else if (overLimit(vx, robot_.max_linear_velocity) || overLimit(vy, robot_.max_linear_velocity) ||
           overLimit(wz, robot_.max_angular_velocity)) {
    std::ostringstream os;
    os << "base twist (" << vx << ", " << vy << ", " << wz << ") exceeds the limits ("
       << robot_.max_linear_velocity << " m/s, " << robot_.max_angular_velocity << " rad/s)";
    why = os.str();
  }
  if (!why.empty()) {
    base_.setZero();
    ++counters_.base_rejected;
    return why;
  }
  if (holo)
    base_ << vx, vy, wz;
  else
    base_ << vx, wz;
  ++counters_.base_accepted;
  return "";
}

std::string CommandGate::onArmCommand(std::int64_t stamp_ns, const std::vector<std::string>& names,
                                      const std::vector<double>& velocities, bool require_stamp) {
  if (require_stamp && stamp_ns != stamp_ns_) {
    ++counters_.arm_stale;
    return "stale arm command (stamp " + std::to_string(stamp_ns) + " ns, state " +
           std::to_string(stamp_ns_) + " ns)";
  }
  arm_answered_ = true;
  const int n = robot_.nArm();
  std::string why;
  Eigen::VectorXd v = Eigen::VectorXd::Zero(n);
  if (static_cast<int>(velocities.size()) != n) {
    why = "arm command has " + std::to_string(velocities.size()) + " velocities, expected " +
          std::to_string(n);
  } else if (!names.empty() && static_cast<int>(names.size()) != n) {
    why = "arm command has " + std::to_string(names.size()) + " names, expected " + std::to_string(n);
  } else {
    std::vector<bool> seen(static_cast<std::size_t>(n), false);
    for (int i = 0; i < n && why.empty(); ++i) {
      int j = i;
      if (!names.empty()) {
        j = -1;
        for (int k = 0; k < n; ++k)
          if (robot_.arm_joints[static_cast<std::size_t>(k)] == names[static_cast<std::size_t>(i)]) j = k;
        if (j < 0 || seen[static_cast<std::size_t>(j)]) {
          why = "arm command names unknown or repeated joint '" + names[static_cast<std::size_t>(i)] + "'";
          break;
        }
        seen[static_cast<std::size_t>(j)] = true;
      }
      const double x = velocities[static_cast<std::size_t>(i)];
      if (!std::isfinite(x)) why = "arm command contains NaN or Inf";
      else if (overLimit(x, robot_.arm_velocity[j])) {
        std::ostringstream os;
        os << "arm command " << x << " rad/s for " << robot_.arm_joints[static_cast<std::size_t>(j)]
           << " exceeds its limit " << robot_.arm_velocity[j];
        why = os.str();
      }
      v[j] = x;
    }
  }
  if (!why.empty()) {
    arm_.setZero();
    ++counters_.arm_rejected;
    return why;
  }
  arm_ = v;
  ++counters_.arm_accepted;
  return "";
}

Eigen::VectorXd CommandGate::command() const {
  Eigen::VectorXd c(base_.size() + arm_.size());
  c << base_, arm_;
  return c;
}

void CommandGate::zero() {
  base_.setZero();
  arm_.setZero();
}

}  // namespace ehc_sim
