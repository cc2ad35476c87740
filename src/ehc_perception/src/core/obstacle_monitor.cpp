#include "ehc_perception/obstacle_monitor.h"

#include "ehc_common/config_node.h"
#include "ehc_control/joint_state.h"
#include "ehc_perception/point_cloud_layout.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <unordered_set>

using ehc_common::requireRange;

namespace ehc_perception {

void ObstacleMonitorParams::validate() const {
  const char* o = "ObstacleMonitorParams";
  ehc_common::requirePositive(o, "node.state_timeout", state_timeout);
  requireRange(o, "node.exclusion_timeout", exclusion_timeout, 0.01, 10.0);
  requireRange(o, "node.max_insert_rate_hz", max_insert_rate_hz, 0.01, 100.0);
  requireRange(o, "node.max_input_points", max_input_points, 1, 10000000);
  requireRange(o, "node.cloud_voxel", cloud_voxel, 0.0, 1.0);
  requireRange(o, "node.max_cloud_points", max_cloud_points, 1, 1000000);
  requireRange(o, "node.points_per_update", points_per_update, 1, 1000000);
}

std::string ObstacleMonitorParams::summary() const {
  std::ostringstream os;
  os << "state timeout " << state_timeout << " s, exclusion timeout " << exclusion_timeout
     << " s, clouds inserted at <= " << max_insert_rate_hz << " Hz, at most " << max_input_points
     << " points read per cloud, decimated to one point per "
     << cloud_voxel << " m voxel" << (cloud_voxel > 0.0 ? "" : " (off)") << ", at most " << max_cloud_points
     << " points per cloud, ray-cast " << points_per_update << " per update";
  return os.str();
}

ObstacleMonitorParams loadObstacleMonitorParams(const ehc_common::ConfigNode& n) {
  ObstacleMonitorParams p;
  p.state_timeout = n.get("state_timeout", p.state_timeout);
  p.exclusion_timeout = n.get("exclusion_timeout", p.exclusion_timeout);
  p.max_insert_rate_hz = n.get("max_insert_rate_hz", p.max_insert_rate_hz);
  p.max_input_points = n.get("max_input_points", p.max_input_points);
  p.cloud_voxel = n.get("cloud_voxel", p.cloud_voxel);
  p.max_cloud_points = n.get("max_cloud_points", p.max_cloud_points);
  p.points_per_update = n.get("points_per_update", p.points_per_update);
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
      field_(map, ehc_control::RobotCollisionModel(model_.urdfXml(), model_.config().arm_joints,
                                                   map.links.empty() ? model_.config().checked_links : map.links)),
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

PointList ObstacleMonitor::boundCloud(const PointList& input, int* after_voxel, int* after_budget) const {
  // The budget first: no per-point work on the points beyond it (a no-op on a cloud the node
  // read within the same budget).
  const auto read_budget = static_cast<std::size_t>(params_.max_input_points);
  const PointList budgeted = input.size() > read_budget ? budgetPoints(input, read_budget) : PointList();
  const PointList& points = input.size() > read_budget ? budgeted : input;
  if (after_budget) *after_budget = static_cast<int>(points.size());
  PointList kept;
  kept.reserve(std::min(points.size(), static_cast<std::size_t>(1) << 16));
  if (params_.cloud_voxel > 0.0) {
    // Voxel keys packed in 3 x 21 bits (+-1 048 576 voxels per axis: 20 km at 2 cm); points
    // beyond that are not obstacles of a mobile manipulator and are dropped.
    const float inv = static_cast<float>(1.0 / params_.cloud_voxel);
    constexpr std::int64_t kHalf = 1 << 20;
    std::unordered_set<std::uint64_t> seen;
    seen.reserve(1 << 14);
    for (const Eigen::Vector3f& p : points) {
      if (!p.allFinite()) continue;
      const Eigen::Vector3f v = (p * inv).array().floor();
      if ((v.array().abs() >= static_cast<float>(kHalf)).any()) continue;
      const std::uint64_t key = (static_cast<std::uint64_t>(static_cast<std::int64_t>(v.x()) + kHalf) << 42) |
                                (static_cast<std::uint64_t>(static_cast<std::int64_t>(v.y()) + kHalf) << 21) |
                                static_cast<std::uint64_t>(static_cast<std::int64_t>(v.z()) + kHalf);
      if (seen.insert(key).second) kept.push_back(p);
    }
  } else {
    for (const Eigen::Vector3f& p : points)
      if (p.allFinite()) kept.push_back(p);
  }
  if (after_voxel) *after_voxel = static_cast<int>(kept.size());
  const auto insert_budget = static_cast<std::size_t>(params_.max_cloud_points);
  return kept.size() <= insert_budget ? kept : budgetPoints(kept, insert_budget);
}

ObstacleMonitor::CloudInsertion ObstacleMonitor::queueCloud(double now, const PointList& points,
                                                            const Eigen::Vector3d& sensor_origin) {
  if (!sensor_origin.allFinite()) throw std::invalid_argument("[ObstacleMonitor] sensor origin is not finite");
  CloudInsertion r;
  r.received = static_cast<int>(points.size());
  r.replaced = static_cast<int>(queuedPoints());
  queue_.points = boundCloud(points, &r.after_voxel, &r.after_budget);
  queue_.next = 0;
  queue_.origin = sensor_origin;
  r.queued = static_cast<int>(queue_.points.size());
  r.self_filtered = stateFresh(now);
  // The robot as it is when the cloud arrives: it moves while the cloud is inserted.
  if (r.self_filtered) queue_.link_poses = field_.linkPoses(model_, base_, q_);
  else queue_.link_poses.reset();
  return r;
}

ObstacleMonitor::CloudInsertion ObstacleMonitor::insertCloud(double now, const PointList& points,
                                                             const Eigen::Vector3d& sensor_origin) {
  CloudInsertion r = queueCloud(now, points, sensor_origin);
  r.stats = insertQueued(queuedPoints());
  return r;
}

ObstacleDistanceField::InsertStats ObstacleMonitor::insertQueued(std::size_t max_points) {
  const std::size_t n = std::min(max_points, queuedPoints());
  if (n == 0) return {};
  const auto first = queue_.points.begin() + static_cast<std::ptrdiff_t>(queue_.next);
  const PointList chunk(first, first + static_cast<std::ptrdiff_t>(n));
  queue_.next += n;
  return field_.insertCloud(chunk, queue_.origin, queue_.link_poses ? &*queue_.link_poses : nullptr);
}

bool ObstacleMonitor::stateFresh(double now, double* stamp) const {
  if (!t_joints_ || !t_base_) return false;
  if (stamp) *stamp = std::max(*t_joints_, *t_base_);
  return now - std::min(*t_joints_, *t_base_) <= params_.state_timeout;
}

ObstacleReport ObstacleMonitor::update(double now) {
  ObstacleReport r;
  r.inserted = insertQueued(static_cast<std::size_t>(params_.points_per_update));
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

ObstacleLockstepCycle::ObstacleLockstepCycle(double publish_rate_hz) : publish_limiter_(publish_rate_hz) {
  if (!(std::isfinite(publish_rate_hz) && publish_rate_hz > 0.0))
    throw std::invalid_argument("[ObstacleLockstepCycle] publish_rate_hz " + std::to_string(publish_rate_hz) +
                                " must be finite and > 0");
}

std::optional<ObstacleLockstepCycle::State> ObstacleLockstepCycle::jointState(StampNs stamp) {
  joints_ = stamp;
  return complete();
}

std::optional<ObstacleLockstepCycle::State> ObstacleLockstepCycle::odometry(StampNs stamp) {
  odom_ = stamp;
  return complete();
}

std::optional<ObstacleLockstepCycle::State> ObstacleLockstepCycle::complete() {
  if (joints_ == 0 || joints_ != odom_) return std::nullopt;
  State s;
  s.stamp = joints_;
  joints_ = 0;
  if (last_ != 0 && s.stamp < last_) publish_limiter_.reset();  // simulator reset
  last_ = s.stamp;
  s.publish = publish_limiter_.accept(stampSeconds(s.stamp));
  return s;
}

}  // namespace ehc_perception
