#pragma once
// One library object on a table, seen once by the simulated hand camera: the single-view depth
// cloud a grasp generator gets (ehc_object_library cloud, tests of grasps on everyday objects).
// The object is dropped on the table and left to settle in Bullet for one second, then the
// camera looks at its centre from `view`. ROS-free.

#include "ehc_perception/grasp_generator.h"
#include "ehc_sim/object_library.h"
#include "ehc_sim/sim_config.h"

#include <Eigen/Geometry>

#include <string>

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

/// The object `name` of `library` on a 0.8 x 1.2 m table (top at 0.75 m, centre (1.9, 0)), the
/// robot of `sim` at the origin, depth noise of `sim` seeded with `seed`.
ObjectViewCloud objectViewCloud(const ehc_sim::ObjectLibrary& library, const std::string& name, const ObjectView& view,
                                const ehc_sim::SimConfig& sim, unsigned seed);

}  // namespace ehc_bringup
