#pragma once
// ObstacleDistanceField: an OctoMap occupancy octree built from point clouds (rays from the
// sensor origin clear free space, end points mark occupied voxels) and FCL distance queries
// between the robot's collision shapes and the octree. For every link closer than the
// influence distance: closest point pair, unit normal (obstacle -> link) and distance.
// Exclusion zones (spheres) hide parts of the map from the distance queries without erasing
// them: the object the hand is about to grasp or holds, which it must touch.
// The robot's shapes: ehc_control::RobotCollisionModel (the links it was built with);
// its gripper fingers are posed fully open by default (linkPoses), the widest they get.
// ROS-free (OctoMap + FCL inside); not thread-safe.

#include "ehc_perception/grasp_generator.h"  // PointList
#include "ehc_control/robot_collision_model.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_control {
class WholeBodyModel;
}  // namespace ehc_control

namespace ehc_perception {

struct ObstacleMapConfig {
  double resolution = 0.02;          ///< m, voxel edge (2-5 cm)
  double max_range = 3.0;            ///< m, longer rays only clear space
  double prob_hit = 0.7, prob_miss = 0.4;
  double clamp_min = 0.12, clamp_max = 0.97;
  double occupancy_threshold = 0.5;
  double min_height = 0.03;          ///< m (world z); lower points (the floor) are ignored
  double self_filter_padding = 0.03; ///< m; points this close to the robot are its own
  double influence_distance = 0.30;  ///< m; farther link-obstacle pairs are not reported
  /// The links checked (in code: tests, tools). Empty = robot.yaml's robot.collision.checked_links
  /// (ObstacleMonitor; itself empty = every link with collision geometry). Robot-specific, so
  /// never read from the generic obstacle_node.yaml.
  std::vector<std::string> links;

  void validate() const;  ///< throws std::invalid_argument "[ObstacleDistanceField] ..."
  std::string summary() const;
};

/// Reads an `obstacle_map` mapping (all fields optional).
ObstacleMapConfig loadObstacleMapConfig(const ehc_common::ConfigNode& node);

struct LinkObstacleDistance {
  std::string link;
  Eigen::Vector3d link_point = Eigen::Vector3d::Zero();      ///< world
  Eigen::Vector3d obstacle_point = Eigen::Vector3d::Zero();  ///< world
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();         ///< unit, obstacle -> link
  double distance = 0.0;                                     ///< m, <= 0: penetration
};

/// A sphere of the map that distance queries ignore (occupied voxels whose centre is inside).
struct ExclusionZone {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  ///< world
  double radius = 0.0;                               ///< m, in [0, kMaxRadius]
  static constexpr double kMaxRadius = 1.0;
  bool contains(const Eigen::Vector3d& p) const { return (p - centre).norm() <= radius; }
  /// True if `p` lies in one of `zones`.
  static bool inAny(const std::vector<ExclusionZone>& zones, const Eigen::Vector3d& p) {
    for (const ExclusionZone& z : zones)
      if (z.contains(p)) return true;
    return false;
  }
  bool operator==(const ExclusionZone& o) const { return centre == o.centre && radius == o.radius; }
};

struct OcTreeExclusion;  // octree_shape_distance.h

class ObstacleDistanceField {
 public:
  /// `robot`: built with config.links (its links() are the ones the field checks, in order).
  ObstacleDistanceField(const ObstacleMapConfig& config, const ehc_control::RobotCollisionModel& robot);
  ~ObstacleDistanceField();
  ObstacleDistanceField(ObstacleDistanceField&&) noexcept;
  ObstacleDistanceField& operator=(ObstacleDistanceField&&) noexcept;

  struct InsertStats {
    int input = 0, non_finite = 0, below_min_height = 0, robot = 0, inserted = 0;
  };
  /// Inserts a cloud given in the world frame, with rays from `sensor_origin` (world).
  /// `link_poses` (world, model link order), if given, removes the robot's own points.
  /// Throws std::invalid_argument on a non-finite origin or wrong-sized link_poses.
  InsertStats insertCloud(const PointList& points, const Eigen::Vector3d& sensor_origin,
                          const std::vector<Eigen::Isometry3d>* link_poses = nullptr);
  /// Marks every voxel whose centre lies in the axis-aligned box as occupied (static priors,
  /// tests).
  void addOccupiedBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max);
  void clear();
  /// Counts the map's changes (insertCloud with points kept, addOccupiedBox, clear): equal
  /// revisions, the same map (the exclusion zones are not part of it).
  std::uint64_t revision() const;

  enum class Cell { Unknown, Free, Occupied };
  Cell cell(const Eigen::Vector3d& p) const;
  std::size_t occupiedLeafCount() const;

  /// Replaces the exclusion zones (empty: none). Throws std::invalid_argument on a non-finite
  /// centre or a radius outside [0, ExclusionZone::kMaxRadius]; the zones are then unchanged.
  void setExclusionZones(const std::vector<ExclusionZone>& zones);
  const std::vector<ExclusionZone>& exclusionZones() const { return zones_; }

  /// Closest obstacle of each link within the influence distance (links without an obstacle
  /// in range are omitted), ignoring occupied voxels inside the exclusion zones.
  /// `link_poses`: world poses in robot().links() order.
  std::vector<LinkObstacleDistance> distances(const std::vector<Eigen::Isometry3d>& link_poses) const;
  /// The same with `zones` instead of the field's exclusion zones, for a configuration other than
  /// the robot's own (a planned one): neither the field's zones nor the seeds its queries keep
  /// for the next cycle are read or changed, and a penetration reads <= 0 without its depth
  /// (unsigned distance). Throws std::invalid_argument as setExclusionZones.
  std::vector<LinkObstacleDistance> distances(const std::vector<Eigen::Isometry3d>& link_poses,
                                              const std::vector<ExclusionZone>& zones) const;
  /// World poses of robot().links() from the whole-body model (which holds the finger joints
  /// at 0), a finger link moved by robot().fingerOffset(link, finger_opening).
  /// `finger_opening` (m per finger): default std::nullopt = each finger at its upper limit,
  /// i.e. the gripper fully open, the widest it gets: the sim and the real gripper open during
  /// the approach, and the map must keep the open fingers clear of obstacles.
  std::vector<Eigen::Isometry3d> linkPoses(const ehc_control::WholeBodyModel& model,
                                           const Eigen::Vector3d& base_pose,
                                           const Eigen::VectorXd& q,
                                           std::optional<double> finger_opening = std::nullopt) const;

  const ObstacleMapConfig& config() const { return config_; }
  /// The robot model's summary and how linkPoses poses the fingers by default.
  std::string summary() const;
  const ehc_control::RobotCollisionModel& robot() const { return robot_; }
  /// Writes the octree (OctoMap binary .bt) for inspection with octovis.
  void writeBinary(const std::string& path) const;

 private:
  struct Impl;
  ObstacleMapConfig config_;
  ehc_control::RobotCollisionModel robot_;
  std::vector<ExclusionZone> zones_;
  std::unique_ptr<Impl> impl_;
  /// The distance loop of both distances(): `excluding` nullptr = no zones; `seeded_queries`:
  /// start from and update the per-shape seeds (the robot's own configuration only).
  std::vector<LinkObstacleDistance> query(const std::vector<Eigen::Isometry3d>& link_poses,
                                          const OcTreeExclusion* excluding, bool seeded_queries) const;
};

}  // namespace ehc_perception
