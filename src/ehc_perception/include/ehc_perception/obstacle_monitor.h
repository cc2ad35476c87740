#pragma once
// ObstacleMonitor: the logic of ehc_obstacle_node around an ObstacleDistanceField, ROS-free and
// unit-tested without a master. It holds the robot state (arm joints parsed by
// ehc_control::armPositionsFromJointState, base pose) with its stamps, rate-limits cloud
// insertions, removes the robot's own points while the state is fresh, expires the exclusion
// list, and decides each cycle what to publish: the link-obstacle distances stamped with the
// newest state, or nothing while the state is missing or stale (the controller's watchdog then
// stops the robot). Times are seconds of one clock: the node passes each input's receipt time
// on its own ROS clock, never a header stamp (a sender's clock offset must not make a dead state
// look fresh), as the controller's watchdogs do.
// ObstacleLockstepCycle (below): when the node publishes in lock-step, on the states' stamps.

#include "ehc_control/robot_config.h"
#include "ehc_control/whole_body_model.h"
#include "ehc_perception/obstacle_distance_field.h"
#include "ehc_perception/rate_limiter.h"
#include "ehc_perception/stamp.h"

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_perception {

struct ObstacleMonitorParams {
  double state_timeout = 0.2;       ///< s: no distances with a joint state or odometry this old
  double exclusion_timeout = 0.5;   ///< s: an older exclusion list is dropped
  double max_insert_rate_hz = 5.0;  ///< clouds inserted at most this often
  /// Work per cloud is bounded, whatever the camera sends (a full 640x480 D435 frame is 307 200
  /// points, a 1280x720 one 921 600; the rays of each inserted point cost up to max_range /
  /// resolution voxel updates). First a point budget: at most this many points of a cloud are
  /// read (point_cloud_layout.h PointBudget: an organised cloud on an even grid of its rows and
  /// columns, 640x480 every second row and column; nothing is done with the others, not even
  /// their conversion). At the map's 3 m range, 640x480 read every second pixel leaves 1.8 cm
  /// between points, under one 2 cm voxel.
  int max_input_points = 80000;
  /// Then m, one point per voxel of this edge is kept (the first, in cloud order); 0 = off.
  double cloud_voxel = 0.02;
  /// then at most this many points are inserted (an even stride over the decimated points).
  int max_cloud_points = 3000;
  /// A queued cloud (queueCloud: the node) is ray-cast this many points per update(), i.e. per
  /// publish cycle, so no cycle stalls on a whole cloud and the distances keep their rate
  /// (3000 points at 300 per 50 Hz cycle: one cloud per 0.2 s = max_insert_rate_hz 5).
  int points_per_update = 300;
  void validate() const;            ///< throws "[ObstacleMonitorParams] ..."
  std::string summary() const;
};

/// Reads state_timeout, exclusion_timeout, max_insert_rate_hz, max_input_points, cloud_voxel,
/// max_cloud_points and points_per_update of the obstacle node's `node` mapping (all optional).
ObstacleMonitorParams loadObstacleMonitorParams(const ehc_common::ConfigNode& node);

/// What ObstacleMonitor::update decided.
struct ObstacleReport {
  enum class Status {
    Publish,      ///< publish `distances` stamped `stamp`
    StateStale,   ///< joint state or odometry missing or older than state_timeout: publish nothing
  };
  Status status = Status::StateStale;
  double stamp = 0.0;  ///< newest state time (the node: its receipt time) (Publish only)
  std::vector<LinkObstacleDistance> distances;
  bool exclusions_expired = false;  ///< the exclusion list was dropped in this update
  ObstacleDistanceField::InsertStats inserted;  ///< queued cloud points ray-cast in this update
};
const char* toString(ObstacleReport::Status s);

class ObstacleMonitor {
 public:
  /// Builds the whole-body model and the distance field (map.links must be robot links).
  /// Throws std::invalid_argument "[ObstacleMonitor] ..." otherwise.
  ObstacleMonitor(const ehc_control::RobotConfig& robot, const ObstacleMapConfig& map,
                  const ObstacleMonitorParams& params);

  /// Joint state stamped `t`. Returns "" if accepted, else why not (state unchanged).
  std::string setJointState(double t, const std::vector<std::string>& names,
                            const std::vector<double>& positions);
  /// Base pose (x, y, yaw) stamped `t`. Returns "" if accepted, else why not.
  std::string setBasePose(double t, const Eigen::Vector3d& base_pose);
  /// Exclusion list received at/stamped `t` (replaces the previous one; empty = none). Returns
  /// "" if accepted, else why not (the previous list stays).
  std::string setExclusionZones(double t, const std::vector<ExclusionZone>& zones);

  /// Rate limit: true if a cloud arriving at `now` is to be inserted (and counts it as the
  /// latest insertion), false if the previous one is younger than 1 / max_insert_rate_hz.
  bool acceptCloud(double now);
  struct CloudInsertion {
    ObstacleDistanceField::InsertStats stats;  ///< insertCloud: of the bounded cloud (stats.input = kept)
    int received = 0;            ///< points in the cloud given
    int after_budget = 0;        ///< points left by the point budget (max_input_points)
    int after_voxel = 0;         ///< finite points left by the voxel decimation (cloud_voxel)
    int queued = 0;              ///< points of the bounded cloud (<= max_cloud_points)
    int replaced = 0;            ///< points of an unfinished queued cloud this one replaced
    bool self_filtered = false;  ///< false: no fresh state, the robot's own points stay in
  };
  /// Queues a world-frame cloud seen from `sensor_origin` (world), bounded (boundCloud), with
  /// the robot's link poses at `now` (fresh state only) for removing its own points; update()
  /// ray-casts points_per_update of it per call. A newer cloud replaces an unfinished one.
  CloudInsertion queueCloud(double now, const PointList& points, const Eigen::Vector3d& sensor_origin);
  /// queueCloud, then the whole bounded cloud at once (stats filled).
  CloudInsertion insertCloud(double now, const PointList& points, const Eigen::Vector3d& sensor_origin);
  /// Ray-casts up to `max_points` of the queued cloud; returns what they did.
  ObstacleDistanceField::InsertStats insertQueued(std::size_t max_points);
  /// Points of the queued cloud not inserted yet.
  std::size_t queuedPoints() const { return queue_.points.size() - queue_.next; }
  /// The bounded cloud insertCloud inserts: at most max_input_points of `points` (budgetPoints:
  /// even stride; the node reads a message within the same budget, PointBudget), non-finite
  /// points dropped, one point per cloud_voxel voxel (the first), then at most
  /// max_cloud_points (even stride, order kept). `after_voxel` and `after_budget` (optional)
  /// receive the counts after the voxel step and after the budget.
  PointList boundCloud(const PointList& points, int* after_voxel = nullptr, int* after_budget = nullptr) const;

  /// The cycle at `now`: ray-casts points_per_update queued points, drops an expired exclusion
  /// list, computes the distances. Throws what ObstacleDistanceField::distances throws.
  ObstacleReport update(double now);

  /// Both joint state and odometry received and the older one at most state_timeout old;
  /// `stamp` (optional) receives the newer stamp.
  bool stateFresh(double now, double* stamp = nullptr) const;

  const ObstacleMonitorParams& params() const { return params_; }
  const ehc_control::WholeBodyModel& model() const { return model_; }
  const ObstacleDistanceField& field() const { return field_; }
  /// The map, e.g. for static priors (ObstacleDistanceField::addOccupiedBox).
  ObstacleDistanceField& field() { return field_; }

 private:
  ObstacleMonitorParams params_;
  ehc_control::WholeBodyModel model_;
  ObstacleDistanceField field_;
  Eigen::VectorXd q_;
  Eigen::Vector3d base_ = Eigen::Vector3d::Zero();
  std::optional<double> t_joints_, t_base_, t_exclusions_;
  RateLimiter insert_limiter_{5.0};  ///< max_insert_rate_hz (set in the constructor)
  struct QueuedCloud {
    PointList points;
    std::size_t next = 0;
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    std::optional<std::vector<Eigen::Isometry3d>> link_poses;  ///< none: no fresh state
  } queue_;
};

/// ehc_obstacle_node in lock-step (a simulator waits for it; no timer, times are the stamps): a
/// state is the joint state and the odometry of one stamp t. When the second of the pair comes
/// in, the state is complete: the node takes the clouds and exclusion lists stamped before t,
/// publishes the distances at t if `publish` (due: publish_rate_hz on the states' stamps,
/// RateLimiter; a state stamped before the previous one, a simulator reset, restarts the rate),
/// then acknowledges t. A zero stamp never completes a state. A joint state completes at most one
/// state: a second odometry of the same stamp does not complete another, a second joint state
/// does. ROS-free; stamps in ns (stamp.h).
class ObstacleLockstepCycle {
 public:
  /// Throws std::invalid_argument "[ObstacleLockstepCycle] ..." unless publish_rate_hz > 0.
  explicit ObstacleLockstepCycle(double publish_rate_hz);
  struct State {
    StampNs stamp = 0;
    bool publish = false;  ///< the distances at `stamp` are due
  };
  /// A joint state stamped `stamp` was accepted or not (the pair completes either way); the
  /// completed state, if this completes one.
  std::optional<State> jointState(StampNs stamp);
  /// An odometry stamped `stamp`; as jointState.
  std::optional<State> odometry(StampNs stamp);

 private:
  std::optional<State> complete();
  RateLimiter publish_limiter_;
  StampNs joints_ = 0, odom_ = 0;  ///< the pending pair's stamps
  StampNs last_ = 0;               ///< the last completed state's stamp
};

}  // namespace ehc_perception
