#include "ehc_perception/obstacle_monitor.h"

#include "ehc_control/config_node.h"
#include "ehc_control/joint_state.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace ehc_perception {

void ObstacleMonitorParams::validate() const {
  const char* o = "ObstacleMonitorParams";
  ehc_control::requirePositive(o, "node.state_timeout", state_timeout);
  ehc_control::requireRange(o, "node.exclusion_timeout", exclusion_timeout, 0.01, 10.0);
  ehc_control::requireRange(o, "node.max_insert_rate_hz", max_insert_rate_hz, 0.01, 100.0);
}

std::string ObstacleMonitorParams::summary() const {
  std::ostringstream os;
  os << "state timeout " << state_timeout << " s, exclusion timeout " << exclusion_timeout
     << " s, clouds inserted at <= " << max_insert_rate_hz << " Hz";
  return os.str();
}

ObstacleMonitorParams loadObstacleMonitorParams(const ehc_control::ConfigNode& n) {
  ObstacleMonitorParams p;
  p.state_timeout = n.get("state_timeout", p.state_timeout);
  p.exclusion_timeout = n.get("exclusion_timeout", p.exclusion_timeout);
  p.max_insert_rate_hz = n.get("max_insert_rate_hz", p.max_insert_rate_hz);
  n.validate(p);
  return p;
}

const char* toString(ObstacleReport::Status s) {
  switch (s) {
    case ObstacleReport::Status::Publish: return "publish";
    case ObstacleReport::Status::StateStale: return "state_stale";
  }
  return "?";
}

ObstacleMonitor::ObstacleMonitor(const ehc_control::RobotConfig& robot, const ObstacleMapConfig& map,
                                 const ObstacleMonitorParams& params)
    : params_(params),
      model_(robot),
      field_(map, ehc_control::RobotCollisionModel(model_.urdfXml(), model_.config().arm_joints, map.links)),
      q_(Eigen::VectorXd::Constant(model_.nArm(), std::nan(""))) {
  params_.validate();
  insert_limiter_ = RateLimiter(params_.max_insert_rate_hz);
  for (const auto& l : field_.robot().links())
    if (!model_.hasLink(l.name))
      throw std::invalid_argument("[ObstacleMonitor] link '" + l.name + "' is not in the robot model");
}

std::string ObstacleMonitor::setJointState(double t, const std::vector<std::string>& names,
                                           const std::vector<double>& positions) {
  const std::string why = ehc_control::armPositionsFromJointState(model_.config().arm_joints, names, positions, &q_);
  if (why.empty()) t_joints_ = t;
  return why;
}

std::string ObstacleMonitor::setBasePose(double t, const Eigen::Vector3d& base_pose) {
  if (!base_pose.allFinite()) return "odometry contains NaN or Inf";
  base_ = base_pose;
  t_base_ = t;
  return "";
}

std::string ObstacleMonitor::setExclusionZones(double t, const std::vector<ExclusionZone>& zones) {
  try {
    field_.setExclusionZones(zones);  // validates (finite centre, radius range)
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  t_exclusions_ = t;
  return "";
}

bool ObstacleMonitor::acceptCloud(double now) {
  return insert_limiter_.accept(now);  // a clock that jumped back (simulator reset) accepts the cloud
}

ObstacleMonitor::CloudInsertion ObstacleMonitor::insertCloud(double now, const PointList& points,
                                                             const Eigen::Vector3d& sensor_origin) {
  CloudInsertion r;
  r.self_filtered = stateFresh(now);
  if (r.self_filtered) {
    const auto poses = field_.linkPoses(model_, base_, q_);
    r.stats = field_.insertCloud(points, sensor_origin, &poses);
  } else {
    r.stats = field_.insertCloud(points, sensor_origin);
  }
  return r;
}

bool ObstacleMonitor::stateFresh(double now, double* stamp) const {
  if (!t_joints_ || !t_base_) return false;
  if (stamp) *stamp = std::max(*t_joints_, *t_base_);
  return now - std::min(*t_joints_, *t_base_) <= params_.state_timeout;
}

ObstacleReport ObstacleMonitor::update(double now) {
  ObstacleReport r;
  if (!stateFresh(now, &r.stamp)) {
    r.status = ObstacleReport::Status::StateStale;
    r.stamp = 0.0;
    return r;
  }
  if (!field_.exclusionZones().empty() && t_exclusions_ && now - *t_exclusions_ > params_.exclusion_timeout) {
    field_.setExclusionZones({});
    r.exclusions_expired = true;
  }
  r.distances = field_.distances(field_.linkPoses(model_, base_, q_));
  r.status = ObstacleReport::Status::Publish;
  return r;
}

}  // namespace ehc_perception
