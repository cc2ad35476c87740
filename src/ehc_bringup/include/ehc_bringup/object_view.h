#pragma once
// Library objects on a table, seen once by the simulated hand camera: the single-view depth
// cloud a grasp generator gets (ehc_object_library cloud and segment, tests of grasps on everyday
// objects). The objects are dropped on the table and left to settle in Bullet for one second,
// then the camera looks at one object's centre from `view`. ROS-free.

#include "ehc_perception/grasp_generator.h"
#include "ehc_sim/object_library.h"
#include "ehc_sim/sim_config.h"

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace ehc_bringup {

struct ObjectView {
  double distance = 0.6;       ///< m, camera to the object's centre
  double elevation_deg = 45.0; ///< above the table plane
  double azimuth_deg = 0.0;    ///< about the vertical; 0 = from -x (the robot's side)
};

struct ObjectViewCloud {
  ehc_perception::PointList points;  ///< world frame (table and object; the floor beyond)
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_world_object = Eigen::Isometry3d::Identity();  ///< after settling
  ehc_sim::BodyConfig body;  ///< the object as the scene has it (mesh, mass, friction)
  double table_height = 0.0;
};

/// Where a library object is dropped: its centre above (x, y) of the table, turned by `yaw`
/// (rad) about the vertical.
struct ObjectPlacement {
  std::string name;
  double x = 1.9, y = 0.0, yaw = 0.0;
};

struct SceneViewCloud {
  ehc_perception::PointList points;  ///< world frame (table and objects; the floor beyond)
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  std::vector<Eigen::Isometry3d> T_world_objects;  ///< after settling, in placement order
  std::vector<ehc_sim::BodyConfig> bodies;         ///< the objects as the scene has them
  double table_height = 0.0;
};

/// The placed objects of `library` on a 0.8 x 1.2 m table (top at 0.75 m, centre (1.9, 0)), the
/// robot of `sim` at the origin, depth noise of `sim` seeded with `seed`; the camera looks at
/// object `look_at`'s settled centre from `view`. Throws std::invalid_argument for no object or
/// `look_at` out of range.
SceneViewCloud sceneViewCloud(const ehc_sim::ObjectLibrary& library, const std::vector<ObjectPlacement>& placements,
                              std::size_t look_at, const ObjectView& view, const ehc_sim::SimConfig& sim, unsigned seed);

/// The object `name` of `library` on a 0.8 x 1.2 m table (top at 0.75 m, centre (1.9, 0)), the
/// robot of `sim` at the origin, depth noise of `sim` seeded with `seed`.
ObjectViewCloud objectViewCloud(const ehc_sim::ObjectLibrary& library, const std::string& name, const ObjectView& view,
                                const ehc_sim::SimConfig& sim, unsigned seed);

}  // namespace ehc_bringup
