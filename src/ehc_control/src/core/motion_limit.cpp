#include "ehc_control/motion_limit.h"

#include "ehc_common/config_node.h"
#include "ehc_common/enum_names.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace ehc_control {

namespace {
const char* kOwner = "MotionLimit";
// The one string map (ehc_msgs/ControllerStatus LIMIT_* carries the same strings).
constexpr ehc_common::EnumNames<MotionLimit, 7> kLimitNames = {{
    {MotionLimit::None, "none"},
    {MotionLimit::JointLimit, "joint_limit"},
    {MotionLimit::Obstacle, "obstacle"},
    {MotionLimit::Singular, "singular"},
    {MotionLimit::SlackSaturated, "slack_saturated"},
    {MotionLimit::BaseNotMoving, "base_not_moving"},
    {MotionLimit::TargetNotSeen, "target_not_seen"},
}};
double wrap(double a) { return std::remainder(a, 2.0 * M_PI); }
}  // namespace

std::string toString(MotionLimit limit) { return ehc_common::enumName(kLimitNames, limit, kOwner); }
MotionLimit motionLimitFromString(const std::string& s) {
  return ehc_common::enumValue(kLimitNames, s, kOwner, "motion limit");
}
std::vector<MotionLimit> motionLimits() { return ehc_common::enumValues(kLimitNames); }

void MotionLimitParams::validate() const {
  using ehc_common::requireRange;
  const char* owner = "MotionLimitParams";
  requireRange(owner, "obstacle_margin", obstacle_margin, 0.0, 1.0);
  requireRange(owner, "singular_manipulability", singular_manipulability, 0.0, 1.0);
  requireRange(owner, "slack_fraction", slack_fraction, 1e-3, 1.0);
  requireRange(owner, "base_window", base_window, 0.01, 100.0);
  requireRange(owner, "base_command", base_command, 1e-4, 10.0);
  requireRange(owner, "base_travel", base_travel, 1e-5, 10.0);
  requireRange(owner, "target_unseen_time", target_unseen_time, 0.01, 1000.0);
}

std::string MotionLimitParams::summary() const {
  std::ostringstream os;
  os << "motion limits: obstacle within d_s + " << obstacle_margin << " m, singular below " << singular_manipulability
     << " x the ready manipulability, slack at " << slack_fraction << " of its bound, base commanded (>= "
     << base_command << ") and moving < " << base_travel << " in " << base_window << " s, target out of view "
     << target_unseen_time << " s";
  return os.str();
}

MotionLimitParams loadMotionLimitParams(const ehc_common::ConfigNode& n) {
  MotionLimitParams p;
  p.obstacle_margin = n.get("obstacle_margin", p.obstacle_margin);
  p.singular_manipulability = n.get("singular_manipulability", p.singular_manipulability);
  p.slack_fraction = n.get("slack_fraction", p.slack_fraction);
  p.base_window = n.get("base_window", p.base_window);
  p.base_command = n.get("base_command", p.base_command);
  p.base_travel = n.get("base_travel", p.base_travel);
  p.target_unseen_time = n.get("target_unseen_time", p.target_unseen_time);
  n.validate(p);  // errors name the file and the section
  return p;
}

std::string MotionLimitReport::detail() const {
  std::ostringstream os;
  os << std::fixed << std::setprecision(3);
  switch (limit) {
    case MotionLimit::None: return "";
    case MotionLimit::JointLimit: os << joint << " " << value << " rad from its limit"; break;
    case MotionLimit::Obstacle:
      os << link << " at d_s " << (value < 0.0 ? "- " : "+ ") << std::abs(value) << " m from the obstacle at ("
         << std::setprecision(2) << obstacle_point.x() << ", " << obstacle_point.y() << ", " << obstacle_point.z() << ")";
      break;
    case MotionLimit::Singular: os << "manipulability " << value << " x the ready pose's"; break;
    case MotionLimit::SlackSaturated: os << "task slack at " << value << " of its bound"; break;
    case MotionLimit::BaseNotMoving: os << "base commanded, moved " << value << " in the window"; break;
    case MotionLimit::TargetNotSeen: os << "target centre out of the image for " << std::setprecision(1) << value << " s"; break;
  }
  return os.str();
}

int pinnedJoint(const RobotConfig& rc, const Eigen::VectorXd& q, double margin) {
  int pinned = -1;
  double closest = margin;
  for (int i = 0; i < q.size(); ++i) {
    const double m = std::min(q[i] - rc.arm_lower[i], rc.arm_upper[i] - q[i]);
    if (m < closest) {
      closest = m;
      pinned = i;
    }
  }
  return pinned;
}

MotionLimitMonitor::MotionLimitMonitor(const WholeBodyModel& model, const QpControllerParams& controller,
                                       const MotionLimitParams& params)
    : model_(model), controller_(controller), params_(params) {
  params_.validate();
  ready_manipulability_ = model_.manipulability(model_.config().arm_ready);
  if (!(ready_manipulability_ > 0.0)) ready_manipulability_ = 1.0;  // a singular ready pose: absolute values
}

int MotionLimitMonitor::pinned(const Eigen::VectorXd& q) const {
  return pinnedJoint(model_.config(), q, controller_.joint_stop + controller_.recovery.pinned_margin);
}

double MotionLimitMonitor::manipulabilityRatio(const Eigen::VectorXd& q) const {
  return model_.manipulability(q) / ready_manipulability_;
}

bool MotionLimitMonitor::obstacleLimit(const std::vector<ObstaclePair>& pairs, MotionLimitReport* r) const {
  const ObstaclePair* held = nullptr;
  double tightest = params_.obstacle_margin;
  for (const ObstaclePair& p : pairs) {
    const double margin = p.distance - controller_.obstacleStop(p.link);
    if (std::isfinite(margin) && margin <= tightest) {
      tightest = margin;
      held = &p;
    }
  }
  if (!held) return false;
  r->limit = MotionLimit::Obstacle;
  r->link = held->link;
  r->obstacle_point = held->obstacle_point;
  r->value = tightest;
  return true;
}

bool MotionLimitMonitor::baseHeld(const Cycle& c, double* moved_out) {
  const int nb = model_.nBase();
  bool commanded = false;
  if (c.command.size() == model_.nDof()) {
    const double linear = nb == 3 ? c.command.head<2>().norm() : std::abs(c.command[0]);
    commanded = linear >= params_.base_command || std::abs(c.command[nb - 1]) >= params_.base_command;
  }
  const Eigen::Vector3d& b = c.base_pose;
  const double moved = std::max((b.head<2>() - anchor_pose_.head<2>()).norm(), std::abs(wrap(b.z() - anchor_pose_.z())));
  if (!have_anchor_ || !commanded || moved >= params_.base_travel) {
    have_anchor_ = true;
    anchor_pose_ = b;
    anchor_t_ = c.t;
    return false;
  }
  *moved_out = moved;
  return c.t - anchor_t_ >= params_.base_window;
}

MotionLimitReport MotionLimitMonitor::update(const Cycle& c) {
  MotionLimitReport r;
  // Histories first: every test below may end the cycle's search.
  if (!c.has_target || c.target_in_fov || !have_seen_) {
    have_seen_ = c.has_target;
    seen_t_ = c.t;
  }
  double base_moved = 0.0;
  const bool base_held = baseHeld(c, &base_moved);
  if (c.q.size() == model_.nArm()) {
    const int j = pinned(c.q);
    if (j >= 0) {
      const RobotConfig& rc = model_.config();
      r.limit = MotionLimit::JointLimit;
      r.joint = rc.arm_joints[static_cast<std::size_t>(j)];
      r.value = std::min(c.q[j] - rc.arm_lower[j], rc.arm_upper[j] - c.q[j]);
      return r;
    }
  }
  if (c.obstacles && obstacleLimit(*c.obstacles, &r)) return r;
  if (c.q.size() == model_.nArm()) {
    const double ratio =
        c.manipulability >= 0.0 ? c.manipulability / ready_manipulability_ : manipulabilityRatio(c.q);
    if (ratio < params_.singular_manipulability) {
      r.limit = MotionLimit::Singular;
      r.value = ratio;
      return r;
    }
  }
  if (c.slack) {
    const double s = c.slack->cwiseAbs().maxCoeff() / controller_.slack_bound;
    if (s >= params_.slack_fraction) {
      r.limit = MotionLimit::SlackSaturated;
      r.value = s;
      return r;
    }
  }
  if (base_held) {
    r.limit = MotionLimit::BaseNotMoving;
    r.value = base_moved;
    return r;
  }
  if (c.has_target && c.t - seen_t_ >= params_.target_unseen_time) {
    r.limit = MotionLimit::TargetNotSeen;
    r.value = c.t - seen_t_;
  }
  return r;
}

}  // namespace ehc_control
